// STEP and IGES through OpenCASCADE's XCAF readers: the document's assembly tree is walked
// into distinct shapes (prototypes) and their placed instances; prototypes are tessellated in
// parallel, then every instance is placed in double by our own arithmetic (the placement a
// manifest uses), so that identical prototypes give bit-identical instances.

#include "tetrapage/formats/CadReader.h"

#include <tbb/parallel_for.h>

#include <BRepBndLib.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Poly_Triangulation.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDF_Tool.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>

#include "PathSupport.h"
#include "tetrapage/formats/Error.h"
#include "tetrapage/formats/Manifest.h"
#include "tetrapage/formats/MeshReader.h"
#include "tetrapage/formats/Progress.h"

namespace tetrapage {
namespace {

// OCCT's translators keep global state (static parameters, the XCAF application): one file is
// translated at a time; tessellation, the long part, runs in parallel.
std::mutex& translation_mutex() {
  static std::mutex mutex;
  return mutex;
}

// x -> R x + t, as a manifest's instances.
using Placement = Transform;

Placement placement_of(const TopLoc_Location& location) {
  const gp_Trsf transform = location.Transformation();
  Placement rows = identity_transform();
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 4; ++column)
      rows[4 * row + column] = transform.Value(row + 1, column + 1);
  return rows;
}

std::string name_of(const TDF_Label& label) {
  Handle(TDataStd_Name) attribute;
  if (label.IsNull() || !label.FindAttribute(TDataStd_Name::GetID(), attribute)) return {};
  return TCollection_AsciiString(attribute->Get()).ToCString();
}

// A distinct shape of the document and its triangles in its own frame.
struct Prototype {
  TopoDS_Shape shape;
  std::string name;
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  double deflection = 0;  // the absolute deflection asked for
  std::string error;      // why it could not be tessellated
};

struct Instance {
  std::size_t prototype = 0;
  Placement placement{};
  std::string path;
};

// The document's free shapes walked depth first into prototypes and placed instances.
class AssemblyWalk {
 public:
  AssemblyWalk(const Handle(XCAFDoc_ShapeTool) & tool, std::string stem)
      : tool_(tool), stem_(std::move(stem)) {}

  void walk_free_shapes() {
    TDF_LabelSequence roots;
    tool_->GetFreeShapes(roots);
    std::vector<TDF_Label> labels;
    for (Standard_Integer i = 1; i <= roots.Length(); ++i) labels.push_back(roots.Value(i));
    const auto segments = sibling_segments(labels, {});
    for (std::size_t i = 0; i < labels.size(); ++i)
      walk(labels[i], TopLoc_Location(), segments[i], 0);
  }

  std::vector<Prototype> prototypes;
  std::vector<Instance> instances;

 private:
  static constexpr int kMaxDepth = 256;

  // Each sibling's path segment: its instance's name, else its shape's, else the file's
  // stem; "#k" numbers siblings that share one.
  std::vector<std::string> sibling_segments(const std::vector<TDF_Label>& labels,
                                            const std::vector<TDF_Label>& referred) const {
    std::vector<std::string> names;
    for (std::size_t i = 0; i < labels.size(); ++i) {
      std::string name = name_of(labels[i]);
      if (name.empty() && i < referred.size()) name = name_of(referred[i]);
      names.push_back(name.empty() ? stem_ : name);
    }
    std::map<std::string, int> count, seen;
    for (const auto& name : names) ++count[name];
    for (auto& name : names)
      if (count[name] > 1) name += "#" + std::to_string(seen[name]++);
    return names;
  }

  void walk(const TDF_Label& label, const TopLoc_Location& location, const std::string& path,
            int depth) {
    if (depth > kMaxDepth)
      throw FormatError("assembly nested deeper than " + std::to_string(kMaxDepth) + " at '" +
                        path + "'");
    if (!XCAFDoc_ShapeTool::IsAssembly(label)) {
      instances.push_back({prototype_of(label, path), placement_of(location), path});
      return;
    }
    TDF_LabelSequence components;
    XCAFDoc_ShapeTool::GetComponents(label, components);
    std::vector<TDF_Label> children, referred;
    for (Standard_Integer i = 1; i <= components.Length(); ++i) {
      TDF_Label shape;
      if (!XCAFDoc_ShapeTool::GetReferredShape(components.Value(i), shape)) continue;
      children.push_back(components.Value(i));
      referred.push_back(shape);
    }
    const auto segments = sibling_segments(children, referred);
    for (std::size_t i = 0; i < children.size(); ++i)
      walk(referred[i], location * XCAFDoc_ShapeTool::GetLocation(children[i]),
           path + "/" + segments[i], depth + 1);
  }

  std::size_t prototype_of(const TDF_Label& label, const std::string& path) {
    TCollection_AsciiString entry;
    TDF_Tool::Entry(label, entry);
    const auto [it, added] = by_entry_.try_emplace(entry.ToCString(), prototypes.size());
    if (added) {
      std::string name = name_of(label);
      if (name.empty()) name = path.substr(path.rfind('/') + 1);
      prototypes.push_back({XCAFDoc_ShapeTool::GetShape(label), std::move(name), {}, {}, 0, {}});
    }
    return it->second;
  }

  Handle(XCAFDoc_ShapeTool) tool_;
  std::string stem_;
  std::map<std::string, std::size_t> by_entry_;
};

void tessellate(Prototype& prototype, const TessellationOptions& options) {
  Bnd_Box box;
  BRepBndLib::Add(prototype.shape, box);
  if (box.IsVoid()) return;  // no geometry: points or empty compounds
  const double diagonal = std::sqrt(box.SquareExtent());
  prototype.deflection =
      options.relative_deflection ? options.deflection * diagonal : options.deflection;
  if (!(prototype.deflection > 0)) {
    prototype.error = "its size gives a deflection of " + std::to_string(prototype.deflection);
    return;
  }
  BRepMesh_IncrementalMesh mesher(prototype.shape, prototype.deflection, Standard_False,
                                  options.angular_deflection, Standard_False);
  if (!mesher.IsDone()) {
    prototype.error = "OpenCASCADE's mesher failed";
    return;
  }
  std::size_t face_number = 0;
  for (TopExp_Explorer faces(prototype.shape, TopAbs_FACE); faces.More();
       faces.Next(), ++face_number) {
    const TopoDS_Face& face = TopoDS::Face(faces.Current());
    TopLoc_Location location;
    const Handle(Poly_Triangulation) mesh = BRep_Tool::Triangulation(face, location);
    if (mesh.IsNull()) {
      prototype.error = "face " + std::to_string(face_number) + " has no triangulation";
      return;
    }
    const gp_Trsf transform = location.Transformation();
    const auto base = static_cast<std::uint32_t>(prototype.vertices.size());
    for (Standard_Integer i = 1; i <= mesh->NbNodes(); ++i) {
      const gp_Pnt p = mesh->Node(i).Transformed(transform);
      prototype.vertices.push_back({p.X(), p.Y(), p.Z()});
    }
    // A reversed face's triangles are wound against its outward normal.
    const bool reversed = face.Orientation() == TopAbs_REVERSED;
    for (Standard_Integer i = 1; i <= mesh->NbTriangles(); ++i) {
      Standard_Integer a = 0, b = 0, c = 0;
      mesh->Triangle(i).Get(a, b, c);
      if (reversed) std::swap(b, c);
      prototype.triangles.push_back(
          {base + std::uint32_t(a - 1), base + std::uint32_t(b - 1), base + std::uint32_t(c - 1)});
    }
  }
}

void tessellate_all(std::vector<Prototype>& prototypes, const TessellationOptions& options,
                    const std::filesystem::path& path) {
  Progress progress("tessellating " + path.filename().string(), prototypes.size(),
                    options.show_progress);
  std::mutex progress_mutex;
  tbb::parallel_for(std::size_t(0), prototypes.size(), [&](std::size_t i) {
    try {
      tessellate(prototypes[i], options);
    } catch (const Standard_Failure& failure) {
      prototypes[i].error = std::string("OpenCASCADE: ") + failure.GetMessageString();
    }
    const std::lock_guard lock(progress_mutex);
    progress.advance();
  });
  progress.finish();
}

// Every instance placed: a part each (instances of a shape that failed are skipped or fail).
TriangleSoup place_instances(const std::vector<Prototype>& prototypes,
                             const std::vector<Instance>& instances,
                             const TessellationOptions& options, const std::string& file,
                             ReadReport& report) {
  TriangleSoup soup;
  for (const Instance& instance : instances) {
    const Prototype& prototype = prototypes[instance.prototype];
    if (!prototype.error.empty()) {
      if (!options.skip_bad_parts)
        throw InputError(file + ": part '" + instance.path + "' (" + prototype.name +
                         ") failed to tessellate: " + prototype.error +
                         " (--skip-bad-parts leaves it out)");
      report.skipped_parts.push_back(instance.path + ": " + prototype.error);
      continue;
    }
    if (prototype.triangles.empty()) continue;
    if (soup.vertices.size() + prototype.vertices.size() >
        std::numeric_limits<std::uint32_t>::max())
      throw InputError(file + ": more vertices than a soup can index at part '" + instance.path +
                       "'");
    const std::uint32_t part = soup.add_part(prototype.name, instance.path);
    const auto base = static_cast<std::uint32_t>(soup.vertices.size());
    for (const Vec3& p : prototype.vertices)
      soup.vertices.push_back(apply_transform(instance.placement, p));
    report.tessellation_deflection = std::max(
        report.tessellation_deflection, prototype.deflection * largest_stretch(instance.placement));
    for (const TriangleIndices& t : prototype.triangles) {
      ++report.triangles_read;
      const TriangleIndices placed{t[0] + base, t[1] + base, t[2] + base};
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
          is_degenerate_triangle(soup.vertices[placed[0]], soup.vertices[placed[1]],
                                 soup.vertices[placed[2]])) {
        ++report.degenerate_dropped;
        continue;
      }
      soup.triangles.push_back(placed);
      soup.part_of.push_back(part);
    }
  }
  return soup;
}

bool is_iges_path(const std::filesystem::path& path) {
  const std::string extension = detail::lower_extension(path);
  return extension == ".iges" || extension == ".igs";
}

// Reads the file with one of OCCT's XCAF readers and transfers it into `document`.
template <class Reader>
bool transfer(const std::string& file, const char* kind, Handle(TDocStd_Document) & document) {
  Reader reader;
  reader.SetNameMode(Standard_True);
  if (reader.ReadFile(file.c_str()) != IFSelect_RetDone)
    throw FormatError(file + ": OpenCASCADE cannot read it as " + kind);
  return reader.Transfer(document);
}

// Translates the file into an XCAF document (under the translation lock).
Handle(TDocStd_Document) translate(const std::filesystem::path& path, ReadReport& report) {
  const std::string file = path.string();
  Handle(XCAFApp_Application) application = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) document;
  application->NewDocument("MDTV-XCAF", document);
  report.format = is_iges_path(path) ? "iges" : "step";
  const bool translated = is_iges_path(path)
                              ? transfer<IGESCAFControl_Reader>(file, "IGES", document)
                              : transfer<STEPCAFControl_Reader>(file, "STEP", document);
  if (!translated)
    throw FormatError(file + ": OpenCASCADE read it but could not translate its shapes");
  return document;
}

void silence_occt_messages() {
  static std::once_flag once;
  std::call_once(once, [] {
    // Its parser prints to the terminal; what matters reaches the user as our error.
    Message::DefaultMessenger()->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
  });
}

}  // namespace

void set_deflection(TessellationOptions& options, const std::string& text, std::string_view what) {
  std::string number = text;
  const bool relative = !number.empty() && number.back() == '%';
  if (relative) number.pop_back();
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(number, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != number.size() || number.empty() || !(value > 0) || !std::isfinite(value))
    throw InputError(std::string(what) + " '" + text +
                     "': expected a positive length (0.01) or percentage (0.1%)");
  options.relative_deflection = relative;
  options.deflection = relative ? value / 100 : value;
}

bool is_cad_path(const std::filesystem::path& path) {
  const std::string extension = detail::lower_extension(path);
  return extension == ".step" || extension == ".stp" || extension == ".p21" || is_iges_path(path);
}

TriangleSoup read_cad(const std::filesystem::path& path, const TessellationOptions& options,
                      ReadReport* report) {
  const auto start = std::chrono::steady_clock::now();
  ReadReport local;
  ReadReport& out = report != nullptr ? *report : local;
  out = ReadReport{};
  out.path = path.string();
  const std::string file = path.string();
  if (!(options.deflection > 0) || !std::isfinite(options.deflection))
    throw InputError(file + ": the deflection must be a positive number, not " +
                     std::to_string(options.deflection));
  if (!(options.angular_deflection > 0) || !(options.angular_deflection <= 3.14159265358979))
    throw InputError(file + ": the angular deflection must be in (0, pi] radians, not " +
                     std::to_string(options.angular_deflection));
  {
    std::error_code error;
    const auto bytes = std::filesystem::file_size(path, error);
    std::ifstream probe(path, std::ios::binary);
    if (error || !probe) throw IoError(file + ": cannot open the file");
    out.bytes = bytes;
  }
  silence_occt_messages();
  std::vector<Prototype> prototypes;
  std::vector<Instance> instances;
  {
    const std::lock_guard lock(translation_mutex());
    try {
      Handle(TDocStd_Document) document = translate(path, out);
      double metres_per_unit = 0.001;
      XCAFDoc_DocumentTool::GetLengthUnit(document, metres_per_unit);
      if (std::fabs(metres_per_unit - 0.001) > 1e-12)
        throw FormatError(file + ": OpenCASCADE translated it into units of " +
                          std::to_string(metres_per_unit) + " m, not millimetres");
      AssemblyWalk walk(XCAFDoc_DocumentTool::ShapeTool(document->Main()), path.stem().string());
      walk.walk_free_shapes();
      prototypes = std::move(walk.prototypes);
      instances = std::move(walk.instances);
      XCAFApp_Application::GetApplication()->Close(document);
    } catch (const Standard_Failure& failure) {
      throw FormatError(file + ": OpenCASCADE failed reading it: " + failure.GetMessageString());
    }
  }
  out.length_unit = "mm";
  if (instances.empty()) throw InputError(file + ": the file holds no shape");
  tessellate_all(prototypes, options, path);
  TriangleSoup soup = place_instances(prototypes, instances, options, file, out);
  if (soup.triangles.empty())
    throw InputError(file + ": no triangle (no shape with faces was tessellated)");
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return soup;
}

}  // namespace tetrapage
