// The OpenCASCADE half of STEP and IGES reading, in the CAD module: the file translated by
// OCCT's XCAF readers, the document's assembly tree walked into distinct shapes (prototypes)
// and their placed instances, the prototypes tessellated in parallel. formats' read_cad places
// the instances (in the caller, by the arithmetic a manifest uses).

#include <tbb/parallel_for.h>

#include <BRepAdaptor_Surface.hxx>
#include <BRepBndLib.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepTools.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <IGESCAFControl_Reader.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Poly_Triangulation.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <Standard_OutOfMemory.hxx>
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
#include <atomic>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <new>
#include <thread>

#include "CadIsolation.h"
#include "CadModule.h"
#include "StepPrescan.h"
#include "tetrapage/formats/base/ByteSize.h"
#include "tetrapage/formats/base/Error.h"
#include "tetrapage/formats/base/Progress.h"
#include "tetrapage/formats/mesh/Manifest.h"

namespace tetrapage::detail {
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
  TessellatedShape mesh;
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
  std::vector<ShapeInstance> instances;

 private:
  static constexpr int kMaxDepth = kMaxAssemblyDepth;

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
      prototypes.push_back({XCAFDoc_ShapeTool::GetShape(label), {std::move(name), {}, {}, 0, {}}});
    }
    return it->second;
  }

  Handle(XCAFDoc_ShapeTool) tool_;
  std::string stem_;
  std::map<std::string, std::size_t> by_entry_;
};

// What OCCT's mesher holds for a face meshed into `triangles`: measured on a sphere of radius
// 10 mm (one face), 300 MB at 100,000 triangles, 1.0 GB at 250,000, and past 21 GB at 2.5M
// (stopped): 3 KB a triangle, times (triangles / 100,000)^0.34 past that.
double mesher_bytes(double triangles) {
  constexpr double kBytesPerTriangle = 3072, kLinearUpTo = 1e5, kGrowth = 0.34;
  return kBytesPerTriangle * triangles * std::max(1.0, std::pow(triangles / kLinearUpTo, kGrowth));
}

// The triangles OCCT's mesher will make of a shape at a finer deflection, and the memory it
// will hold for them, estimated before it runs.
struct MeshEstimate {
  double triangles = 0, bytes = 0;
};

// The estimate of `shape` at `fine`: a mesh at `coarse` whose curved faces' counts are scaled
// by coarse / fine (a curved surface's count grows as 1 / deflection, a plane's does not). The
// coarse mesh is removed afterwards.
MeshEstimate estimate_mesh(const TopoDS_Shape& shape, double coarse, double fine, double angular) {
  BRepMesh_IncrementalMesh mesher(shape, coarse, Standard_False, angular, Standard_False);
  MeshEstimate estimate;
  for (TopExp_Explorer faces(shape, TopAbs_FACE); faces.More(); faces.Next()) {
    const TopoDS_Face& face = TopoDS::Face(faces.Current());
    TopLoc_Location location;
    const Handle(Poly_Triangulation) mesh = BRep_Tool::Triangulation(face, location);
    if (mesh.IsNull()) continue;
    const bool plane = BRepAdaptor_Surface(face, Standard_False).GetType() == GeomAbs_Plane;
    const double triangles = double(mesh->NbTriangles()) * (plane ? 1.0 : coarse / fine);
    estimate.triangles += triangles;
    estimate.bytes += mesher_bytes(triangles);
  }
  BRepTools::Clean(shape);
  return estimate;
}

// Refuses (in out.error) a deflection finer than the default whose estimated triangles exceed
// the limit, or whose mesher would exceed the reading's memory (--cad-memory; without it, half
// the machine's, for the caller and everything else): it would run for minutes and take
// gigabytes before failing.
bool within_triangle_limit(const TopoDS_Shape& shape, double diagonal,
                           const TessellationOptions& options, TessellatedShape& out) {
  const double coarse = TessellationOptions{}.deflection * diagonal;
  if (options.max_triangles == 0 || !(out.deflection < coarse)) return true;
  const MeshEstimate mesh = estimate_mesh(shape, coarse, out.deflection, options.angular_deflection);
  const double estimate = mesh.triangles;
  if (options.show_progress)
    std::fprintf(stderr, "tetrapage: %s: about %.3g triangles at a deflection of %g mm\n",
                 out.name.c_str(), estimate, out.deflection);
  const std::uint64_t memory =
      options.memory_limit != 0 ? options.memory_limit : machine_memory() / 2;
  char text[320];
  if (estimate > double(options.max_triangles)) {
    std::snprintf(
        text, sizeof text,
        "would make about %.3g triangles at a deflection of %g mm, more than the limit of %llu "
        "(a larger --deflection makes fewer; --max-cad-triangles raises the limit)",
        estimate, out.deflection, static_cast<unsigned long long>(options.max_triangles));
  } else if (mesh.bytes > double(memory)) {
    std::snprintf(
        text, sizeof text,
        "would make about %.3g triangles at a deflection of %g mm, for which OpenCASCADE's "
        "mesher needs about %s, above the reading's memory of %s (a larger --deflection "
        "makes fewer; --cad-memory raises the memory)",
        estimate, out.deflection,
        format_byte_size(std::uint64_t(mesh.bytes)).c_str(),
        format_byte_size(memory).c_str());
  } else {
    return true;
  }
  out.error = text;
  out.refused = true;
  return false;
}

void tessellate(Prototype& prototype, const TessellationOptions& options) {
  TessellatedShape& out = prototype.mesh;
  Bnd_Box box;
  BRepBndLib::Add(prototype.shape, box);
  if (box.IsVoid()) return;  // no geometry: points or empty compounds
  const double diagonal = std::sqrt(box.SquareExtent());
  out.deflection = options.relative_deflection ? options.deflection * diagonal : options.deflection;
  if (!(out.deflection > 0)) {
    out.error = "its size gives a deflection of " + std::to_string(out.deflection);
    return;
  }
  if (!within_triangle_limit(prototype.shape, diagonal, options, out)) return;
  BRepMesh_IncrementalMesh mesher(prototype.shape, out.deflection, Standard_False,
                                  options.angular_deflection, Standard_False);
  if (!mesher.IsDone()) {
    out.error = "OpenCASCADE's mesher failed";
    return;
  }
  std::size_t face_number = 0;
  for (TopExp_Explorer faces(prototype.shape, TopAbs_FACE); faces.More();
       faces.Next(), ++face_number) {
    const TopoDS_Face& face = TopoDS::Face(faces.Current());
    TopLoc_Location location;
    const Handle(Poly_Triangulation) mesh = BRep_Tool::Triangulation(face, location);
    if (mesh.IsNull()) {
      out.error = "face " + std::to_string(face_number) + " has no triangulation";
      return;
    }
    const gp_Trsf transform = location.Transformation();
    const auto base = static_cast<std::uint32_t>(out.vertices.size());
    for (Standard_Integer i = 1; i <= mesh->NbNodes(); ++i) {
      const gp_Pnt p = mesh->Node(i).Transformed(transform);
      out.vertices.push_back({p.X(), p.Y(), p.Z()});
    }
    // A reversed face's triangles are wound against its outward normal.
    const bool reversed = face.Orientation() == TopAbs_REVERSED;
    for (Standard_Integer i = 1; i <= mesh->NbTriangles(); ++i) {
      Standard_Integer a = 0, b = 0, c = 0;
      mesh->Triangle(i).Get(a, b, c);
      if (reversed) std::swap(b, c);
      out.triangles.push_back(
          {base + std::uint32_t(a - 1), base + std::uint32_t(b - 1), base + std::uint32_t(c - 1)});
    }
  }
}

void tessellate_one(Prototype& prototype, const TessellationOptions& options) {
  try {
    tessellate(prototype, options);
  } catch (const Standard_Failure& failure) {
    prototype.mesh.error = std::string("OpenCASCADE: ") + failure.GetMessageString();
  }
}

// Tessellates every prototype on `threads` threads of its own (std::thread: a child made by
// fork() cannot use TBB's workers), or on TBB's when `threads` is 0.
void tessellate_all(std::vector<Prototype>& prototypes, const TessellationOptions& options,
                    const std::filesystem::path& path, unsigned threads) {
  Progress progress("tessellating " + path.filename().string(), prototypes.size(),
                    options.show_progress);
  std::mutex progress_mutex;
  const auto tessellate_at = [&](std::size_t i) {
    tessellate_one(prototypes[i], options);
    const std::lock_guard lock(progress_mutex);
    progress.advance();
  };
  if (threads == 0) {
    tbb::parallel_for(std::size_t(0), prototypes.size(), tessellate_at);
  } else {
    std::atomic<std::size_t> next{0};
    std::vector<std::jthread> workers;
    for (unsigned t = 0; t < std::min<std::size_t>(threads, prototypes.size()); ++t)
      workers.emplace_back([&] {
        for (std::size_t i = next++; i < prototypes.size(); i = next++) tessellate_at(i);
      });
  }
  progress.finish();
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
Handle(TDocStd_Document) translate(const std::filesystem::path& path) {
  const std::string file = path.string();
  Handle(XCAFApp_Application) application = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) document;
  application->NewDocument("MDTV-XCAF", document);
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

// The file translated and its shapes tessellated (on TBB's threads when `threads` is 0).
CadContent read_occt_content(const std::filesystem::path& path, const TessellationOptions& options,
                        unsigned threads) {
  const std::string file = path.string();
  silence_occt_messages();
  std::vector<Prototype> prototypes;
  CadContent content;
  {
    const std::lock_guard lock(translation_mutex());
    try {
      Handle(TDocStd_Document) document = translate(path);
      double metres_per_unit = 0.001;
      XCAFDoc_DocumentTool::GetLengthUnit(document, metres_per_unit);
      if (std::fabs(metres_per_unit - 0.001) > 1e-12)
        throw FormatError(file + ": OpenCASCADE translated it into units of " +
                          std::to_string(metres_per_unit) + " m, not millimetres");
      AssemblyWalk walk(XCAFDoc_DocumentTool::ShapeTool(document->Main()), path.stem().string());
      walk.walk_free_shapes();
      prototypes = std::move(walk.prototypes);
      content.instances = std::move(walk.instances);
      XCAFApp_Application::GetApplication()->Close(document);
    } catch (const Standard_OutOfMemory&) {
      throw std::bad_alloc();
    } catch (const Standard_Failure& failure) {
      throw FormatError(file + ": OpenCASCADE failed reading it: " + failure.GetMessageString());
    }
  }
  if (content.instances.empty()) throw InputError(file + ": the file holds no shape");
  tessellate_all(prototypes, options, path, threads);
  for (Prototype& prototype : prototypes) content.shapes.push_back(std::move(prototype.mesh));
  return content;
}

}  // namespace tetrapage::detail
