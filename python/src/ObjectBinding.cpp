// tetrapage.FlyingObject: the collision query over batches of poses (GIL released), the step's
// contacts as a structured array, distance, and time of impact.

#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "Bindings.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage::python {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One row of QueryAnswer.contacts.
struct ContactRecord {
  std::uint32_t part;
  std::uint32_t component;
  std::uint64_t environment_triangle;
  std::int64_t object_triangle;  // -1: the object was checked as a solid
  std::uint32_t dynamic_part;
  std::uint8_t shape;  // 0 none, 1 point, 2 segment, 3 polygon
  std::uint8_t point_count;
  double point[3];  // the mean of points: a point both triangles share
  double points[6][3];
  double environment_normal[3];
  double object_normal[3];
};

// One row of FlyingObject.times_of_impact.
struct ImpactRecord {
  std::uint8_t impact;  // 0 none, 1 hit, 2 unresolved
  double free_until;
  double contact_at;
  std::int64_t environment_triangle;  // -1: no contact found
  std::uint32_t environment_part;
  std::int64_t object_triangle;
  std::uint32_t iterations;
};

// One row of FlyingObject.distances.
struct DistanceRecord {
  std::uint8_t separation;  // 0 touching, 1 apart, 2 farther
  double distance;
  double lower_bound;
  double upper_bound;
  double on_environment[3];
  double on_object[3];
  std::int64_t environment_triangle;  // -1: none measured
  std::uint32_t environment_part;
  std::int64_t object_triangle;
  std::uint32_t dynamic_part;
  std::uint8_t containment;  // touching without contact: Containment (0 none, 1 object inside, 2
                             // obstacle inside)
  std::uint32_t containing_part;
};

// The step's counters and box become Python objects only when asked for: a caller stepping
// one pose per call pays for the contacts alone.
struct QueryAnswer {
  bool collides = false;
  Containment containment = Containment::none;
  std::uint32_t containing_part = 0;
  std::uint32_t containing_dynamic_part = 0;
  bool outside_model = false;
  py::object contacts;
  StepCounters counters;
  geometry::Box world_box;
};

struct DistanceAnswer {
  DistanceResult result;
};

struct ImpactAnswer {
  ImpactResult result;
};

template <class Enum>
Enum parse_name(const std::string& text, std::initializer_list<std::pair<const char*, Enum>> names,
                const char* what) {
  std::string known;
  for (const auto& [name, value] : names) {
    if (text == name) return value;
    known += (known.empty() ? "" : ", ") + std::string(name);
  }
  throw InputError(std::string(what) + " '" + text + "' is not one of " + known);
}

// Runs `step` on the object's FlyingObject with the GIL released, this object's lock held (one
// thread at a time) and its overlay's shared (no change during a step).
template <class Step>
void run_step(Object& object, Step&& step) {
  py::gil_scoped_release unlocked;
  const StepLocks locks(*object.busy, object.obstacles_lock);
  step(*object.flying);
}

// The locks this thread's steps hold, innermost last (steps nest only through signal handlers).
thread_local std::vector<const void*> locks_of_this_thread;

// A bad pose in a batch is named by its row.
template <class Query>
void for_each_pose(const PoseBatch& batch, const char* what, Query&& query) {
  constexpr std::size_t kPosesBetweenSignalChecks = 1 << 14;  // a few milliseconds
  for (std::size_t k = 0; k < batch.poses.size(); ++k) {
    if (k % kPosesBetweenSignalChecks == kPosesBetweenSignalChecks - 1) {
      // Ctrl-C stops a long batch (the GIL is taken only for the check).
      py::gil_scoped_acquire locked;
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
    try {
      query(k, batch.poses[k]);
    } catch (const InputError& error) {
      throw InputError(batch.single
                           ? std::string(what) + ": " + error.what()
                           : std::string(what) + "[" + std::to_string(k) + "]: " + error.what());
    }
  }
}

void fill_geometry(const geometry::ContactGeometry& g, ContactRecord& record) {
  record.shape = std::uint8_t(g.shape);
  record.point_count = g.count;
  double mean[3] = {0, 0, 0};
  for (int i = 0; i < 6; ++i)
    for (int a = 0; a < 3; ++a) {
      record.points[i][a] = i < g.count ? g.points[i][a] : kNaN;
      if (i < g.count) mean[a] += g.points[i][a] / g.count;
    }
  for (int a = 0; a < 3; ++a) {
    record.point[a] = g.count ? mean[a] : kNaN;
    record.environment_normal[a] = g.count ? g.first_normal[a] : kNaN;
    record.object_normal[a] = g.count ? g.second_normal[a] : kNaN;
  }
}

// The step's triangles are recorded by phase II: their geometry pages in nothing new.
void contact_records(FlyingObject& flying, const QueryResult& result, bool geometry,
                     std::vector<ContactRecord>& records) {
  records.resize(result.contacts.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    const Contact& c = result.contacts[i];
    ContactRecord& record = records[i];
    record.part = c.environment_part;
    record.component = c.environment_component;
    record.environment_triangle = c.environment_triangle;
    record.object_triangle =
        c.object_triangle == Contact::kNoObjectTriangle ? -1 : std::int64_t(c.object_triangle);
    record.dynamic_part = c.dynamic_part;
    fill_geometry(geometry ? flying.contact_geometry(c) : geometry::ContactGeometry{}, record);
  }
}

QueryAnswer answer_of(const QueryResult& result, py::array contacts) {
  QueryAnswer answer;
  answer.collides = result.collides;
  answer.containment = result.containment;
  answer.containing_part = result.containing_part;
  answer.containing_dynamic_part = result.containing_dynamic_part;
  answer.outside_model = result.outside_model;
  answer.contacts = std::move(contacts);
  answer.counters = result.counters;
  answer.world_box = result.world_box;
  return answer;
}

py::object collides(Object& object, py::handle poses, const std::string& accuracy,
                    const std::string& shape, const std::string& motion) {
  const PoseBatch batch = poses_from_array(poses, "poses");
  const QueryOptions options = query_options("first_hit", accuracy, shape, motion);
  py::array_t<bool> answers(py::ssize_t(batch.poses.size()));
  bool* out = answers.mutable_data();
  run_step(object, [&](FlyingObject& flying) {
    QueryResult result;
    for_each_pose(batch, "poses", [&](std::size_t k, const Pose& pose) {
      flying.query(pose, options, result);
      out[k] = result.collides;
    });
  });
  if (batch.single) return py::bool_(out[0]);
  return answers;
}

QueryAnswer query(Object& object, py::handle pose_value, const std::string& mode,
                  const std::string& accuracy, const std::string& shape, const std::string& motion,
                  bool geometry) {
  const PoseBatch batch{{pose_from_array(pose_value, "pose")}, true};
  const QueryOptions options = query_options(mode, accuracy, shape, motion);
  QueryResult result;
  std::vector<ContactRecord> records;
  run_step(object, [&](FlyingObject& flying) {
    for_each_pose(batch, "pose", [&](std::size_t, const Pose& pose) {
      flying.query(pose, options, result);
      contact_records(flying, result, geometry, records);
    });
  });
  return answer_of(result, py::array_t<ContactRecord>(py::ssize_t(records.size()), records.data()));
}

// The point, or NaNs when the answer holds none.
py::array_t<double> point_or_nan(const DistanceResult& r, const geometry::Point& point) {
  const double nan[3] = {kNaN, kNaN, kNaN};
  return double_array(has_closest_points(r) ? point.data() : nan, {3});
}

DistanceRecord record_of(const DistanceResult& r) {
  DistanceRecord record{};
  record.separation = std::uint8_t(r.separation);
  record.distance = r.distance;
  record.lower_bound = r.lower_bound;
  record.upper_bound = r.upper_bound;
  const bool measured = r.closest.has_triangle();
  for (int a = 0; a < 3; ++a) {
    record.on_environment[a] = has_closest_points(r) ? r.on_environment[a] : kNaN;
    record.on_object[a] = has_closest_points(r) ? r.on_object[a] : kNaN;
  }
  record.environment_triangle = measured ? std::int64_t(r.closest.environment_triangle) : -1;
  record.environment_part = r.closest.environment_part;
  record.object_triangle = measured ? std::int64_t(r.closest.object_triangle) : -1;
  record.dynamic_part = r.closest.dynamic_part;
  record.containment = std::uint8_t(r.containment);
  record.containing_part = r.containing_part;
  return record;
}

py::array distances(Object& object, py::handle poses, double max_distance) {
  const PoseBatch batch = poses_from_array(poses, "poses");
  std::vector<DistanceRecord> records(batch.poses.size());
  run_step(object, [&](FlyingObject& flying) {
    DistanceResult result;
    for_each_pose(batch, "poses", [&](std::size_t k, const Pose& pose) {
      flying.distance(pose, DistanceOptions{max_distance}, result);
      records[k] = record_of(result);
    });
  });
  return py::array_t<DistanceRecord>(py::ssize_t(records.size()), records.data());
}

// As `tetrapage fly --query toi`: row 0 the first pose alone, row k the motion from pose k - 1.
py::array times_of_impact(Object& object, py::handle poses, double tolerance,
                          py::handle max_iterations_value) {
  const ImpactOptions options{
      tolerance,
      std::uint32_t(whole_number(max_iterations_value, "max_iterations", 1, 0xffffffffu))};
  const PoseBatch batch = poses_from_array(poses, "poses");
  std::vector<ImpactRecord> records(batch.poses.size());
  run_step(object, [&](FlyingObject& flying) {
    for_each_pose(batch, "poses", [&](std::size_t k, const Pose& pose) {
      const ImpactResult r = flying.time_of_impact(batch.poses[k == 0 ? 0 : k - 1], pose, options);
      records[k] = {std::uint8_t(r.impact),
                    r.free_until,
                    r.contact_at,
                    r.contact.has_triangle() ? std::int64_t(r.contact.environment_triangle) : -1,
                    r.contact.environment_part,
                    r.contact.has_triangle() ? std::int64_t(r.contact.object_triangle) : -1,
                    r.iterations};
    });
  });
  return py::array_t<ImpactRecord>(py::ssize_t(records.size()), records.data());
}

py::object optional_triangle(bool present, std::uint64_t id) {
  return present ? py::object(py::int_(id)) : py::object(py::none());
}

void bind_answers(py::module_& module) {
  PYBIND11_NUMPY_DTYPE(ContactRecord, part, component, environment_triangle, object_triangle,
                       dynamic_part, shape, point_count, point, points, environment_normal,
                       object_normal);
  PYBIND11_NUMPY_DTYPE(DistanceRecord, separation, distance, lower_bound, upper_bound,
                       on_environment, on_object, environment_triangle, environment_part,
                       object_triangle, dynamic_part, containment, containing_part);
  module.attr("OBJECT_INSIDE_OBSTACLE") = std::uint8_t(Containment::object_inside_obstacle);
  module.attr("OBSTACLE_INSIDE_OBJECT") = std::uint8_t(Containment::obstacle_inside_object);
  module.attr("TOUCHING") = std::uint8_t(Separation::touching);
  module.attr("APART") = std::uint8_t(Separation::apart);
  module.attr("FARTHER") = std::uint8_t(Separation::farther);
  module.attr("contact_dtype") = py::dtype::of<ContactRecord>();
  module.attr("distance_dtype") = py::dtype::of<DistanceRecord>();
  PYBIND11_NUMPY_DTYPE(ImpactRecord, impact, free_until, contact_at, environment_triangle,
                       environment_part, object_triangle, iterations);
  module.attr("IMPACT_NONE") = std::uint8_t(Impact::none);
  module.attr("IMPACT_HIT") = std::uint8_t(Impact::hit);
  module.attr("IMPACT_UNRESOLVED") = std::uint8_t(Impact::unresolved);
  module.attr("impact_dtype") = py::dtype::of<ImpactRecord>();

  py::class_<QueryAnswer>(module, "QueryAnswer", R"(One collision query's answer.
collides: surfaces touch, or one body holds the other (containment).
contacts: structured array, one row per contact (first_hit: at most one): part, component,
  environment_triangle, object_triangle (-1 for a solid shape), dynamic_part (0: the index's),
  shape (0 none, 1 point, 2 segment, 3 polygon), point_count, point (a point both triangles
  share, NaN without geometry), points (6, 3), environment_normal, object_normal.
counters: what the step did (dict). world_box: (2, 3).)")
      .def_readonly("collides", &QueryAnswer::collides,
                    "True when the surfaces touch (contacts) or one body holds the other "
                    "(containment); bool(answer) says the same.")
      .def_property_readonly(
          "containment", [](const QueryAnswer& a) { return to_string(a.containment); },
          "A collision without touching surfaces: \"object_inside_obstacle\" (the object lies "
          "inside a closed part: an index with interiors) or \"obstacle_inside_object\" (a part "
          "lies inside the closed object); \"none\" otherwise.")
      .def_readonly("containing_part", &QueryAnswer::containing_part,
                    "The environment part of a containment, its id in Index.parts (4294967294 "
                    "for an inserted obstacle: see containing_dynamic_part); 0 without one.")
      .def_readonly("containing_dynamic_part", &QueryAnswer::containing_dynamic_part,
                    "The id (from Obstacles.insert) of the inserted obstacle that holds the "
                    "object or that it holds; 0 for the index's parts or without a containment.")
      .def_readonly("outside_model", &QueryAnswer::outside_model,
                    "The object's world box lies entirely outside the index's mesh: no triangle "
                    "of the index can touch it (inserted obstacles are still checked).")
      .def_readonly("contacts", &QueryAnswer::contacts,
                    "The contacts, a structured array of tetrapage.contact_dtype (its fields "
                    "above), one row per contact found (first_hit: at most one; a containment "
                    "has none).")
      .def_property_readonly(
          "counters", [](const QueryAnswer& a) { return counters_dict(a.counters); },
          "What the step did, as a new dict: the walk and search (searched, tets_crossed, "
          "tets_visited, tets_overlapping), the shards (shards_touched, shard_misses: paged in "
          "by this step), phases I and II (candidates, leaves_inside_object, repeats, "
          "triangle_tests), the free box (in_free_box, found_free_box), and *_seconds timings.")
      .def_property_readonly(
          "world_box",
          [](const QueryAnswer& a) { return box_array(a.world_box.lo, a.world_box.hi); },
          "(2, 3): the object's world box at the pose (lowest and highest corner, in the "
          "index's coordinates), slightly enlarged over the placement's rounding.")
      .def("__bool__", [](const QueryAnswer& a) { return a.collides; })
      .def("__repr__", [](const QueryAnswer& a) {
        return std::string("<tetrapage.QueryAnswer ") + (a.collides ? "collides" : "free") + ", " +
               std::to_string(py::len(a.contacts)) + " contacts>";
      });

  py::class_<DistanceAnswer>(module, "DistanceAnswer", R"(One distance query's answer: the true
distance lies in [lower_bound, upper_bound] (certified); separation is "touching" (distance 0),
"apart", or "farther" (than max_distance: distance is then the certified lower bound).)")
      .def_property_readonly(
          "separation", [](const DistanceAnswer& a) { return to_string(a.result.separation); },
          "\"touching\" (surfaces touch or one body holds the other, decided as collides() "
          "decides it with its defaults), \"apart\" (within max_distance) or \"farther\".")
      .def_property_readonly(
          "distance", [](const DistanceAnswer& a) { return a.result.distance; },
          "The computed distance between the closest points, in the index's length unit "
          "(Index.length_unit); 0 when touching; when farther, the certified lower bound.")
      .def_property_readonly(
          "lower_bound", [](const DistanceAnswer& a) { return a.result.lower_bound; },
          "A certified lower bound of the true distance, in the index's unit (0 when touching; "
          "at least max_distance when farther).")
      .def_property_readonly(
          "upper_bound", [](const DistanceAnswer& a) { return a.result.upper_bound; },
          "A certified upper bound of the true distance, in the index's unit (0 when touching; "
          "infinity when farther): the gap to lower_bound is the double computation's error.")
      .def_property_readonly(
          "on_environment",
          [](const DistanceAnswer& a) { return point_or_nan(a.result, a.result.on_environment); },
          "The closest point on the environment; NaN when farther or for a containment.")
      .def_property_readonly(
          "on_object",
          [](const DistanceAnswer& a) { return point_or_nan(a.result, a.result.on_object); },
          "The closest point on the object; NaN when farther or for a containment.")
      .def_property_readonly(
          "environment_triangle",
          [](const DistanceAnswer& a) {
            return optional_triangle(a.result.closest.has_triangle(),
                                     a.result.closest.environment_triangle);
          },
          "The closest pair's environment triangle, its id in the index (in an inserted "
          "obstacle: its row in that obstacle's mesh); None when farther or for a containment.")
      .def_property_readonly(
          "environment_part",
          [](const DistanceAnswer& a) { return a.result.closest.environment_part; },
          "The part of environment_triangle, its id in Index.parts (4294967294 for an inserted "
          "obstacle); meaningful only when environment_triangle is not None.")
      .def_property_readonly(
          "object_triangle",
          [](const DistanceAnswer& a) {
            return optional_triangle(a.result.closest.has_triangle(),
                                     a.result.closest.object_triangle);
          },
          "The closest pair's object triangle, its row in the object's triangles; None when "
          "environment_triangle is None.")
      .def_property_readonly(
          "dynamic_part", [](const DistanceAnswer& a) { return a.result.closest.dynamic_part; },
          "The id (from Obstacles.insert) of the inserted obstacle that holds "
          "environment_triangle, or 0 for the index's triangles.")
      .def_property_readonly(
          "containment", [](const DistanceAnswer& a) { return to_string(a.result.containment); },
          "Touching without contact: \"object_inside_obstacle\" or \"obstacle_inside_object\" "
          "(as QueryAnswer.containment); \"none\" otherwise.")
      .def_property_readonly(
          "containing_part", [](const DistanceAnswer& a) { return a.result.containing_part; },
          "The environment part of a containment, its id in Index.parts (4294967294 for an "
          "inserted obstacle); 0 without one.")
      .def_property_readonly(
          "candidates", [](const DistanceAnswer& a) { return a.result.candidates; },
          "How many environment triangles were measured against the object (the query's work; "
          "0 when the collision step found it touching or a free box answered \"farther\").")
      .def_property_readonly(
          "pair_tests", [](const DistanceAnswer& a) { return a.result.pair_tests; },
          "How many triangle pairs had their distance computed.")
      .def("__repr__", [](const DistanceAnswer& a) {
        return std::string("<tetrapage.DistanceAnswer ") + to_string(a.result.separation) + " " +
               std::to_string(a.result.distance) + ">";
      });

  py::class_<ImpactAnswer>(module, "ImpactAnswer", R"(One time-of-impact answer over the motion's
time [0, 1]: impact "none" (certified free), "hit" (first contact in (free_until, contact_at]),
or "unresolved" (max_iterations ran out: free up to free_until).)")
      .def_property_readonly(
          "impact", [](const ImpactAnswer& a) { return to_string(a.result.impact); },
          "\"none\" (certified: nothing touched during the whole motion), \"hit\" or "
          "\"unresolved\" (max_iterations ran out).")
      .def_property_readonly(
          "free_until", [](const ImpactAnswer& a) { return a.result.free_until; },
          "The motion's time in [0, 1] (0 at start, 1 at end) before which nothing touches "
          "(certified); 1 when impact is \"none\".")
      .def_property_readonly(
          "contact_at", [](const ImpactAnswer& a) { return a.result.contact_at; },
          "For a hit, the motion's time in [0, 1] at which the pose collides (decided exactly), "
          "at most tolerance after free_until; 1 when impact is \"none\" or \"unresolved\".")
      .def_property_readonly(
          "environment_triangle",
          [](const ImpactAnswer& a) {
            return optional_triangle(a.result.contact.has_triangle(),
                                     a.result.contact.environment_triangle);
          },
          "The environment triangle of the first contact found at contact_at, its id in the "
          "index (in an inserted obstacle: its row in that obstacle's mesh); None without a "
          "contact (no hit, or a hit that is a containment).")
      .def_property_readonly(
          "environment_part",
          [](const ImpactAnswer& a) { return a.result.contact.environment_part; },
          "The part of environment_triangle, its id in Index.parts (4294967294 for an inserted "
          "obstacle); meaningful only when environment_triangle is not None.")
      .def_property_readonly(
          "object_triangle",
          [](const ImpactAnswer& a) {
            return optional_triangle(a.result.contact.has_triangle(),
                                     a.result.contact.object_triangle);
          },
          "The object triangle of that contact, its row in the object's triangles; None "
          "without a contact.")
      .def_property_readonly(
          "iterations", [](const ImpactAnswer& a) { return a.result.iterations; },
          "How many distance queries the conservative advancement ran (at most "
          "max_iterations).")
      .def("__repr__", [](const ImpactAnswer& a) {
        return std::string("<tetrapage.ImpactAnswer ") + to_string(a.result.impact) +
               " free until " + std::to_string(a.result.free_until) + ">";
      });
}

}  // namespace

StepLocks::StepLocks(std::mutex& busy, const std::shared_ptr<std::shared_mutex>& overlay) {
  refuse_held(&busy, "this object");
  busy_ = std::unique_lock(busy);
  locks_of_this_thread.push_back(&busy);
  if (overlay && !held(overlay.get())) {
    overlay_ = std::shared_lock(*overlay);
    locks_of_this_thread.push_back(overlay.get());
  }
}

StepLocks::~StepLocks() {
  locks_of_this_thread.pop_back();
  if (overlay_.owns_lock()) locks_of_this_thread.pop_back();
}

bool StepLocks::held(const void* lock) {
  return std::find(locks_of_this_thread.begin(), locks_of_this_thread.end(), lock) !=
         locks_of_this_thread.end();
}

void StepLocks::refuse_held(const void* lock, const std::string& what) {
  if (held(lock))
    throw InputError(what +
                     ": a query in progress on this thread holds it (a signal handler ran "
                     "during that query); use it after the query returns");
}

QueryOptions query_options(const std::string& mode, const std::string& accuracy,
                           const std::string& shape, const std::string& motion) {
  QueryOptions options;
  options.mode = parse_name<QueryMode>(
      mode, {{"first_hit", QueryMode::first_hit}, {"all_contacts", QueryMode::all_contacts}},
      "mode");
  options.accuracy = geometry::parse_accuracy(accuracy);
  options.shape = parse_name<ObjectShape>(
      shape, {{"mesh", ObjectShape::mesh}, {"hull", ObjectShape::hull}, {"box", ObjectShape::box}},
      "shape");
  options.motion = parse_name<Motion>(
      motion, {{"discrete", Motion::discrete}, {"swept", Motion::swept}}, "motion");
  return options;
}

py::dict counters_dict(const StepCounters& c) {
  py::dict d;
  d["searched"] = c.searched;
  d["tets_crossed"] = c.tets_crossed;
  d["tets_visited"] = c.tets_visited;
  d["tets_overlapping"] = c.tets_overlapping;
  d["shards_touched"] = c.shards_touched;
  d["shard_misses"] = c.shard_misses;
  d["candidates"] = c.candidates;
  d["leaves_inside_object"] = c.leaves_inside_object;
  d["repeats"] = c.repeats;
  d["triangle_tests"] = c.triangle_tests;
  d["in_free_box"] = c.in_free_box;
  d["found_free_box"] = c.found_free_box;
  d["locate_seconds"] = c.locate_seconds;
  d["search_seconds"] = c.search_seconds;
  d["shard_seconds"] = c.shard_seconds;
  d["test_seconds"] = c.test_seconds;
  d["interior_seconds"] = c.interior_seconds;
  d["free_box_seconds"] = c.free_box_seconds;
  return d;
}

std::shared_ptr<const ObjectModel> model_of(py::handle mesh, py::handle triangles,
                                            std::string_view what) {
  if (triangles.is_none() && py::isinstance<Model>(mesh)) return mesh.cast<const Model&>().model;
  TriangleSoup soup =
      triangles.is_none() ? soup_from_mesh_like(mesh, what) : soup_from_arrays(mesh, triangles);
  py::gil_scoped_release unlocked;  // the BVH and the hull: tens of milliseconds
  return std::make_shared<const ObjectModel>(std::move(soup));
}

Object make_object(const Index& index, py::handle mesh, py::handle triangles) {
  const std::shared_ptr<const ObjectModel> model = model_of(mesh, triangles, "object");
  Object object;
  object.flying = std::make_unique<FlyingObject>(index.index, model);
  return object;
}

void bind_objects(py::module_& module) {
  bind_answers(module);
  py::class_<Model>(module, "Model",
                    R"(An object's model (its triangles, BVH, hull and, when closed, its
interior), built once and shared: Index.object(model) makes a flying object of it at once, on any
thread; Obstacles.insert(model, pose) and ObjectGroup take it too.)")
      .def(py::init([](py::handle mesh, py::handle triangles) {
             return Model{model_of(mesh, triangles, "mesh")};
           }),
           py::arg("mesh"), py::arg("triangles") = py::none(),
           "Model(mesh) with a tetrapage.Mesh, or Model(vertices, triangles).")
      .def_property_readonly(
          "triangles", [](const Model& m) { return m.model->mesh.triangle_count(); },
          "How many triangles its mesh holds, as given (object_triangle is a row of them).")
      .def_property_readonly(
          "closed", [](const Model& m) { return m.model->closed; },
          "Some component is closed (obstacles inside it are reported).")
      .def_property_readonly(
          "bounds", [](const Model& m) { return box_array(m.model->box.lo, m.model->box.hi); },
          "(2, 3): its box in its own frame.")
      .def("__repr__", [](const Model& m) {
        return "<tetrapage.Model " + std::to_string(m.model->mesh.triangle_count()) + " triangles" +
               (m.model->closed ? ", closed>" : ">");
      });
  py::class_<Object>(module, "FlyingObject", R"(A rigid object flying through an Index (made by
Index.object). Poses are (7,) or (K, 7) arrays of tx, ty, tz, qw, qx, qy, qz (a unit quaternion,
as in pose files) or (4, 4) / (K, 4, 4) rigid matrices. Queries release the GIL; one object is
used by one thread at a time (a second waits): give each thread its own object.)")
      .def("collides", &collides, py::arg("poses"), py::kw_only(), py::arg("accuracy") = "exact",
           py::arg("shape") = "mesh", py::arg("motion") = "discrete",
           R"(Whether the object collides at each pose: a bool for one pose, else a (K,) bool array.
accuracy: "exact" (default), "double_eps", "float_eps", "clearance:D" (within D counts).
shape: "mesh" (its triangles, and its inside when closed), "hull", "box".
motion: "discrete" (each pose alone) or "swept" (the hull of the object at the previous and
the current pose: the poses are consecutive steps).)")
      .def("query", &query, py::arg("pose"), py::kw_only(), py::arg("mode") = "first_hit",
           py::arg("accuracy") = "exact", py::arg("shape") = "mesh", py::arg("motion") = "discrete",
           py::arg("geometry") = true,
           "One step at `pose`, with its contacts (mode \"first_hit\" or \"all_contacts\") and "
           "counters: a QueryAnswer. geometry: also where each contact's triangles meet.")
      .def(
          "distance",
          [](Object& object, py::handle pose_value, double max_distance) {
            const PoseBatch batch{{pose_from_array(pose_value, "pose")}, true};
            DistanceAnswer answer;
            run_step(object, [&](FlyingObject& flying) {
              for_each_pose(batch, "pose", [&](std::size_t, const Pose& pose) {
                flying.distance(pose, DistanceOptions{max_distance}, answer.result);
              });
            });
            return answer;
          },
          py::arg("pose"), py::kw_only(),
          py::arg("max_distance") = std::numeric_limits<double>::infinity(),
          "The distance to the environment at `pose`, its closest points and triangles, certified "
          "by bounds: a DistanceAnswer. Beyond max_distance only \"farther\" is answered (cheap).")
      .def("distances", &distances, py::arg("poses"), py::kw_only(),
           py::arg("max_distance") = std::numeric_limits<double>::infinity(),
           "distance() over (K, 7) or (K, 4, 4) poses: a structured array "
           "(tetrapage.distance_dtype; "
           "separation is TOUCHING, APART or FARTHER).")
      .def(
          "times_of_impact", &times_of_impact, py::arg("poses"), py::kw_only(),
          py::arg("tolerance") = 1e-4, py::arg("max_iterations") = 10000,
          "time_of_impact() along (K, 7) or (K, 4, 4) poses, as `tetrapage fly --query toi`: row 0 "
          "the first pose alone, row k the motion from pose k - 1 to pose k. A structured array "
          "(tetrapage.impact_dtype; impact is IMPACT_NONE, IMPACT_HIT or IMPACT_UNRESOLVED).")
      .def(
          "time_of_impact",
          [](Object& object, py::handle start, py::handle end, double tolerance,
             py::handle max_iterations_value) {
            const auto max_iterations =
                std::uint32_t(whole_number(max_iterations_value, "max_iterations", 1, 0xffffffffu));
            const Pose from = pose_from_array(start, "start");
            const Pose to = pose_from_array(end, "end");
            ImpactAnswer answer;
            run_step(object, [&](FlyingObject& flying) {
              answer.result =
                  flying.time_of_impact(from, to, ImpactOptions{tolerance, max_iterations});
            });
            return answer;
          },
          py::arg("start"), py::arg("end"), py::kw_only(), py::arg("tolerance") = 1e-4,
          py::arg("max_iterations") = 10000,
          "The first time in [0, 1] at which the object moving from `start` to `end` (translation "
          "linear, rotation by slerp) touches the environment: an ImpactAnswer whose bracket "
          "(free_until, contact_at] is at most `tolerance` wide.")
      .def(
          "world_box",
          [](Object& object, py::handle pose_value) {
            const Pose pose = pose_from_array(pose_value, "pose");
            geometry::Box box;
            run_step(object, [&](FlyingObject& flying) { box = flying.world_box(pose); });
            return box_array(box.lo, box.hi);
          },
          py::arg("pose"), "The object's world box at `pose`, (2, 3).")
      .def_property(
          "obstacles", [](const Object& o) { return o.obstacles; },
          [](Object& o, py::handle value) { hold_obstacles(o, *o.flying, value); },
          "The tetrapage.Obstacles merged into every query, or None.")
      .def_property_readonly(
          "triangles", [](const Object& o) { return o.flying->object().triangle_count(); },
          "How many triangles the object's mesh holds, as given (object_triangle is a row of "
          "them).")
      .def_property_readonly(
          "closed", [](const Object& o) { return o.flying->closed(); },
          "Some component is closed (obstacles inside it are reported).");
}

}  // namespace tetrapage::python
