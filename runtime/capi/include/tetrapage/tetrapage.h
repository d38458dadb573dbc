/* tetrapage.h - the C API of the tetrapage runtime.
 *
 * Two opaque handles, each with create/release functions:
 *  - tetrapage_index: an opened index file (the coarse mesh stays resident; shards are paged
 *    in on demand under a byte budget that is never exceeded);
 *  - tetrapage_object: a rigid flying object moving through one index; it remembers where it
 *    was (queries along a motion are cheap) and the answer of its last query.
 *
 * Every function that can fail returns a tetrapage_status; on failure tetrapage_last_error()
 * holds a one-line message naming the file, the element and the value at fault. No C++
 * exception ever crosses this interface. Null handles and null output pointers are reported as
 * TETRAPAGE_ERROR_INVALID_ARGUMENT, never dereferenced.
 *
 * Handles are opaque ids, not addresses: every call looks its handle up in a process-wide
 * table. A handle already closed or destroyed (or one never returned by this library, or an
 * object handle passed as an index) is reported as TETRAPAGE_ERROR_STALE_HANDLE; closing or
 * destroying twice is such an error, never a crash. Ids are never reused within a process.
 *
 * Ownership: an object shares ownership of the index it was created from. Closing the index
 * handle while objects live is safe: the handle becomes stale at once (no new object can be
 * created from it), while the objects keep answering queries; the index itself is freed with
 * the last of them.
 *
 * Threads: an index may be shared by any number of objects used from different threads; one
 * object is used from one thread at a time. Error messages are kept per thread.
 *
 * Typical use:
 *
 *   tetrapage_index* index = NULL;
 *   tetrapage_object* object = NULL;
 *   if (tetrapage_open("model.tpi", TETRAPAGE_DEFAULT_BUDGET_BYTES, &index) != TETRAPAGE_OK ||
 *       tetrapage_object_create_from_file(index, "tool.ply", &object) != TETRAPAGE_OK) {
 *     fprintf(stderr, "%s\n", tetrapage_last_error());
 *     ...
 *   }
 *   const double pose[7] = {0.5, 0.5, 0.5, 1, 0, 0, 0};  // tx ty tz qw qx qy qz
 *   int collides = 0;
 *   tetrapage_collide(object, pose, NULL, &collides);  // NULL: the defaults (exact, first hit)
 *   tetrapage_object_destroy(object);
 *   tetrapage_close(index);
 */
#ifndef TETRAPAGE_TETRAPAGE_H
#define TETRAPAGE_TETRAPAGE_H

#include <stddef.h>
#include <stdint.h>

#include "tetrapage/version.h"

/* Marks a call kept for one release after its replacement: compilers warn where it is used. */
#if defined(__GNUC__) || defined(__clang__)
#define TETRAPAGE_DEPRECATED(message) __attribute__((deprecated(message)))
#elif defined(_MSC_VER)
#define TETRAPAGE_DEPRECATED(message) __declspec(deprecated(message))
#else
#define TETRAPAGE_DEPRECATED(message)
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* Version                                                                                     */

/* The library's version, "MAJOR.MINOR.PATCH": TETRAPAGE_VERSION_STRING of the release it was
   built from, which a program compares with the TETRAPAGE_VERSION_STRING it was compiled
   with (tetrapage/version.h) to detect a mismatched shared library. Never null. */
const char* tetrapage_version(void);

/* ------------------------------------------------------------------------------------------ */
/* Status codes and messages                                                                   */

typedef enum tetrapage_status {
  TETRAPAGE_OK = 0,
  /* A file could not be opened, read or written (missing, unreadable): tetrapage::IoError. */
  TETRAPAGE_ERROR_IO = 1,
  /* A file was readable but is not what its format requires (not an index, wrong version,
     truncated, checksum mismatch, malformed mesh): tetrapage::FormatError. */
  TETRAPAGE_ERROR_FORMAT = 2,
  /* Well-formed but unusable input: NaN or infinite coordinates or poses, a non-unit
     quaternion, indices out of range, an empty object, a zero budget, an invalid accuracy:
     tetrapage::InputError. */
  TETRAPAGE_ERROR_INPUT = 3,
  /* A null handle or pointer where one is required. */
  TETRAPAGE_ERROR_INVALID_ARGUMENT = 4,
  /* Memory could not be allocated (std::bad_alloc). */
  TETRAPAGE_ERROR_OUT_OF_MEMORY = 5,
  /* Any other failure (another tetrapage::Error or an unexpected exception). */
  TETRAPAGE_ERROR_INTERNAL = 6,
  /* A non-null handle that names no live index or object: closed or destroyed already, never
     returned by tetrapage, or of the other kind. Never dereferenced. */
  TETRAPAGE_ERROR_STALE_HANDLE = 7
} tetrapage_status;

/* The message of the last call on this thread that returned a status: empty ("") after a
   success. The text stays valid until the next tetrapage call on this thread. Never null. */
const char* tetrapage_last_error(void);

/* A short constant name of a status ("ok", "I/O error", ...); "unknown status" for values
   outside the enumeration. Never null. */
const char* tetrapage_status_string(tetrapage_status status);

/* ------------------------------------------------------------------------------------------ */
/* Index                                                                                       */

typedef struct tetrapage_index tetrapage_index;

/* The budget the C++ API and the command line use by default: 1 GiB of decoded shards (an
   index whose shards are smaller never holds more than they need). */
#define TETRAPAGE_DEFAULT_BUDGET_BYTES ((uint64_t)1 << 30)

/* Opens an index file written by `tetrapage preprocess`, with a budget in bytes for the
   decoded shards held in memory (must be positive; a background thread prefetches the shards
   a motion heads for). On success *index receives a new handle; on failure it is set to
   NULL.
   Errors: TETRAPAGE_ERROR_IO (missing or unreadable file; the message names it),
           TETRAPAGE_ERROR_FORMAT (not an index, wrong version, inconsistent tables),
           TETRAPAGE_ERROR_INPUT (a zero budget, or one smaller than the largest shard: the
           message names the budget, the shard and its size),
           TETRAPAGE_ERROR_INVALID_ARGUMENT (null path or index). */
tetrapage_status tetrapage_open(const char* path, uint64_t budget_bytes, tetrapage_index** index);

/* Releases the handle, which becomes stale. Objects created from it stay usable: the index
   itself is freed with the last of them. A null index is ignored (TETRAPAGE_OK).
   Errors: TETRAPAGE_ERROR_STALE_HANDLE (closed already, or not an index handle). */
tetrapage_status tetrapage_close(tetrapage_index* index);

/* The box of the model's triangles as stored in the index: lo[3] and hi[3].
   Errors: TETRAPAGE_ERROR_INVALID_ARGUMENT (a null argument), TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_index_bounds(const tetrapage_index* index, double lo[3], double hi[3]);

/* The number of parts of the indexed model (a contact's environment_part is below it).
   Errors: TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_index_part_count(const tetrapage_index* index, uint32_t* count);

/* Strings are returned the same way: the text (UTF-8) is copied into `buffer` of `capacity`
   bytes, cut to fit and always NUL-terminated when capacity > 0, and its whole length
   (without the NUL) goes to *length, so that a caller can ask again with a larger buffer.
   `buffer` may be null when capacity is 0. */

/* What the model's file calls part `part` ("CONN_2x5"; "part K" in an index from before part
   names were recorded).
   Errors: TETRAPAGE_ERROR_INPUT (no such part), TETRAPAGE_ERROR_INVALID_ARGUMENT,
           TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_index_part_name(const tetrapage_index* index, uint32_t part, char* buffer,
                                           size_t capacity, size_t* length);

/* Where part `part` sits in the assembly: its instance path ("rack/board_3/U7").
   Errors: as tetrapage_index_part_name. */
tetrapage_status tetrapage_index_part_path(const tetrapage_index* index, uint32_t part, char* buffer,
                                           size_t capacity, size_t* length);

/* The model's length unit ("mm", "m", "in", ...; "" when the index records none).
   Errors: TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_index_length_unit(const tetrapage_index* index, char* buffer, size_t capacity,
                                             size_t* length);

/* A stored triangle by its model-wide id (a contact's environment_triangle): its corners as
   stored, x0 y0 z0 x1 y1 z1 x2 y2 z2, and its part. Pages in the shards that may hold it.
   Errors: TETRAPAGE_ERROR_INPUT (no stored triangle has that id), TETRAPAGE_ERROR_IO and
           TETRAPAGE_ERROR_FORMAT (paging a shard in), TETRAPAGE_ERROR_INVALID_ARGUMENT,
           TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_index_triangle(const tetrapage_index* index, uint64_t id, double corners[9],
                                          uint32_t* part);

/* ------------------------------------------------------------------------------------------ */
/* Flying objects                                                                              */

typedef struct tetrapage_object tetrapage_object;

/* Creates an object from a triangle mesh in its own coordinates: `vertices` holds
   3 * vertex_count doubles (x, y, z per vertex), `triangles` 3 * triangle_count vertex
   indices (0-based). The arrays are copied. On failure *object is set to NULL.
   Errors: TETRAPAGE_ERROR_INPUT (no triangle, a non-finite coordinate, a coordinate beyond
           1e150 in magnitude (distances from its placement could overflow), an index out of
           range, every triangle of zero area),
           TETRAPAGE_ERROR_INVALID_ARGUMENT (a null argument; vertices may be null only when
           vertex_count is 0), TETRAPAGE_ERROR_STALE_HANDLE (a closed index). */
tetrapage_status tetrapage_object_create(tetrapage_index* index, const double* vertices,
                                         size_t vertex_count, const uint32_t* triangles,
                                         size_t triangle_count, tetrapage_object** object);

/* Creates an object from a mesh file (OBJ, PLY, OFF, STL, glTF/GLB, ...; STEP and IGES
   tessellated with the default deflection, in millimetres; all parts merged).
   Errors: TETRAPAGE_ERROR_IO, TETRAPAGE_ERROR_FORMAT, TETRAPAGE_ERROR_INPUT (as the mesh
           readers: the message names the file, the line or element and the value; as
           tetrapage_object_create for the mesh read), TETRAPAGE_ERROR_INVALID_ARGUMENT,
           TETRAPAGE_ERROR_STALE_HANDLE (a closed index). */
tetrapage_status tetrapage_object_create_from_file(tetrapage_index* index, const char* path,
                                                   tetrapage_object** object);

/* Releases the object, whose handle becomes stale (and the index, if it was closed already).
   A null object is ignored (TETRAPAGE_OK).
   Errors: TETRAPAGE_ERROR_STALE_HANDLE (destroyed already, or not an object handle). */
tetrapage_status tetrapage_object_destroy(tetrapage_object* object);

/* ------------------------------------------------------------------------------------------ */
/* Queries                                                                                     */

/* How collisions are decided (docs/USAGE.md, "Index and fly": `--accuracy`; what each mode
   costs and misses: docs/BENCHMARKS.md, "Speed against accuracy"). */
typedef enum tetrapage_accuracy {
  /* Exact signs on the stored coordinates; touching counts. `parameter` is ignored. */
  TETRAPAGE_ACCURACY_EXACT = 0,
  /* Epsilon-threshold floating tests in double / float; `parameter` is the relative epsilon,
     0 for the default. Faster on some inputs, may answer wrongly near contact. */
  TETRAPAGE_ACCURACY_DOUBLE_EPS = 1,
  TETRAPAGE_ACCURACY_FLOAT_EPS = 2,
  /* Everything within distance `parameter` (>= 0) of the environment counts. */
  TETRAPAGE_ACCURACY_CLEARANCE = 3
} tetrapage_accuracy;

/* Parses the accuracy text the command line takes: "exact", "double_eps", "float_eps"
   (optionally ":EPSILON"), "clearance:D".
   Errors: TETRAPAGE_ERROR_INPUT (anything else; the message names the text),
           TETRAPAGE_ERROR_INVALID_ARGUMENT. */
tetrapage_status tetrapage_parse_accuracy(const char* text, tetrapage_accuracy* accuracy,
                                          double* parameter);

/* How finely the object is checked (the C++ ObjectShape): its triangles; the convex hull of
   its placed vertices as a solid; its world axis-aligned box as a solid. Coarser shapes never
   miss a contact of the finer ones under the exact accuracy, and answer yes more often. */
typedef enum tetrapage_object_shape {
  TETRAPAGE_SHAPE_MESH = 0,
  TETRAPAGE_SHAPE_HULL = 1,
  TETRAPAGE_SHAPE_BOX = 2
} tetrapage_object_shape;

/* The pose alone, or the convex hull of the object at the previous and the current pose (the
   box of both boxes for TETRAPAGE_SHAPE_BOX; there is no exact swept mesh: MESH sweeps the
   hull). An object's first query has no previous pose and is discrete. */
typedef enum tetrapage_motion {
  TETRAPAGE_MOTION_DISCRETE = 0,
  TETRAPAGE_MOTION_SWEPT = 1
} tetrapage_motion;

/* ---- Argument structs: how this API grows ----
   A query's options travel in an argument struct whose first field, struct_size, is the size
   of the struct the caller was compiled with; its init function sets struct_size and every
   default. A new option is a new field at the end of its struct, never a new function: the
   library reads the fields that struct_size covers and takes the defaults for the others, so a
   program compiled against an older header keeps its behaviour. A null args pointer means
   every default. A struct_size below sizeof(size_t), or beyond the struct this library knows
   (a program compiled against a newer header), is TETRAPAGE_ERROR_INVALID_ARGUMENT.
   Enumerations are stored as int32_t fields (their values are the enumerators). */

/* tetrapage_query_args.contacts */
#define TETRAPAGE_CONTACTS_FIRST 0 /* stop at the first contact found */
#define TETRAPAGE_CONTACTS_ALL 1   /* collect every contact pair */

typedef struct tetrapage_query_args {
  size_t struct_size;
  int32_t accuracy; /* a tetrapage_accuracy; default TETRAPAGE_ACCURACY_EXACT */
  double parameter; /* the accuracy's epsilon or clearance; default 0 */
  int32_t shape;    /* a tetrapage_object_shape; default TETRAPAGE_SHAPE_MESH */
  int32_t motion;   /* a tetrapage_motion; default TETRAPAGE_MOTION_DISCRETE */
  int32_t contacts; /* TETRAPAGE_CONTACTS_FIRST (default) or _ALL */
  /* TETRAPAGE_CONTACTS_ALL: a query that finds more contacts fails with TETRAPAGE_ERROR_INPUT
     naming the limit, instead of growing without bound; default 1,000,000. */
  uint64_t max_contacts;
} tetrapage_query_args;

/* Sets struct_size and the defaults above. A null args is ignored. */
void tetrapage_query_args_init(tetrapage_query_args* args);

/* The "no triangle" of every hit: no environment triangle (a distance farther than its limit,
   a containment), no object triangle (the object checked as a solid: hull, box, swept), no
   component (a query that does not name it). */
#define TETRAPAGE_NO_TRIANGLE UINT64_MAX
#define TETRAPAGE_NO_OBJECT_TRIANGLE UINT32_MAX
#define TETRAPAGE_NO_COMPONENT UINT32_MAX
/* environment_part of a hit on a dynamic obstacle (tetrapage_obstacles): no part of the index. */
#define TETRAPAGE_DYNAMIC_PART 0xFFFFFFFEu

/* Where a query's answer touches: one environment triangle and one object triangle. Every
   query names its sites with it (contacts, the closest pair of a distance, the first contact
   of a time of impact). */
typedef struct tetrapage_hit {
  /* The triangle's model-wide id (tetrapage_index_triangle), or for a dynamic obstacle its
     index in that obstacle's mesh; TETRAPAGE_NO_TRIANGLE when none. */
  uint64_t environment_triangle;
  uint32_t environment_part;      /* TETRAPAGE_DYNAMIC_PART for a dynamic obstacle */
  uint32_t environment_component; /* the connected component; TETRAPAGE_NO_COMPONENT unnamed */
  uint32_t object_triangle;       /* TETRAPAGE_NO_OBJECT_TRIANGLE for a solid, or none */
  uint32_t dynamic_part;          /* the dynamic obstacle's id, 0 for the index's triangles */
} tetrapage_hit;

/* Places the object at `pose` and decides whether it touches the environment, with the options
   of `args` (null: every default: exact, the object's mesh, discrete, first contact).
   pose: tx, ty, tz, qw, qx, qy, qz (the pose-file order); it maps the object's coordinates x to
   R(q) x + t, and q must be a unit quaternion (up to rounding).
   On success *collides is 1 or 0 and the contacts are kept in the object until its next query
   (tetrapage_contact_count, tetrapage_get_hits, tetrapage_last_query_info).
   Errors: TETRAPAGE_ERROR_INPUT (non-finite pose, non-unit quaternion, a translation beyond
           1e150 in magnitude (distances from there would overflow), an unknown accuracy, shape,
           motion or contacts value, an invalid parameter, more contacts than max_contacts),
           TETRAPAGE_ERROR_IO / TETRAPAGE_ERROR_FORMAT (a shard this query needs could not be
           read or failed its checksum, also when the background prefetcher met the fault
           first: the message names the shard and the file; other shards and other objects
           stay usable), TETRAPAGE_ERROR_INVALID_ARGUMENT (a null object, pose or collides, a
           bad struct_size), TETRAPAGE_ERROR_STALE_HANDLE. After a failure the object holds no
           contact. */
tetrapage_status tetrapage_collide(tetrapage_object* object, const double pose[7],
                                   const tetrapage_query_args* args, int* collides);

/* The number of contacts of the last successful query (first contact only: 0 or 1).
   Errors: TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_contact_count(const tetrapage_object* object, size_t* count);

/* Copies the first min(capacity, count) contacts of the last query to `hits` and their number
   to *written. `hits` may be null when capacity is 0.
   Errors: TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_get_hits(const tetrapage_object* object, tetrapage_hit* hits,
                                    size_t capacity, size_t* written);

/* What the last query did: the counters that explain its time. */
typedef struct tetrapage_query_info {
  int collides;
  /* The object's box lies entirely outside the model's coarse mesh. */
  int outside_model;
  /* The object's box in world coordinates. */
  double world_lo[3];
  double world_hi[3];
  uint32_t tets_crossed;   /* by the walk that located the box */
  uint32_t tets_visited;   /* by the search for the tets overlapping the box */
  uint32_t shards_touched;
  uint32_t shard_misses;   /* shards paged in synchronously */
  uint64_t candidates;     /* environment triangles meeting the object's box (except those
                              of R-tree leaves inside a closed object, apart from its surface) */
  uint64_t triangle_tests; /* triangle pair tests */
  double seconds;          /* locate + search + shards + tests + containment */
  /* Why a query collides without touching surfaces: 0 it does not (or surfaces touch),
     1 a component of the object lies inside a closed component of the environment (an
       index preprocessed with interiors),
     2 a component of the environment lies inside a closed component of the object. */
  int containment;
  uint32_t containing_part;      /* the environment part of a containment */
  uint32_t containing_component; /* the environment component of a containment */
} tetrapage_query_info;

/* Fills *info for the last successful query (all zero before the first one).
   Errors: TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_last_query_info(const tetrapage_object* object,
                                           tetrapage_query_info* info);

/* ------------------------------------------------------------------------------------------ */
/* Contact geometry, distance and time of impact                                              */

/* Where the two triangles of a contact meet, and their normals. */
typedef struct tetrapage_contact_geometry {
  /* 0 none (a contact of a solid: no object triangle), 1 a point, 2 a segment, 3 a polygon
     (coplanar triangles overlapping; corners in order). */
  int shape;
  uint32_t point_count; /* 1, 2 or 3 to 6 */
  double points[6][3];
  double environment_normal[3]; /* unit, right-hand rule of the triangle's corners */
  double object_normal[3];
} tetrapage_contact_geometry;

/* The geometry of contact `contact` (an index < tetrapage_contact_count, as in tetrapage_get_hits)
   of the object's last query, at that query's pose. Computed in double from exactly decided
   topology: each point lies within 2^-40 of the coordinates' magnitude of the exact intersection.
   Errors: TETRAPAGE_ERROR_INPUT (no such contact), TETRAPAGE_ERROR_IO / _FORMAT (the
           triangle's shard could not be read), TETRAPAGE_ERROR_INVALID_ARGUMENT,
           TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_get_contact_geometry(tetrapage_object* object, size_t contact,
                                                tetrapage_contact_geometry* geometry);

/* ---- Distance ---- */

typedef struct tetrapage_distance_args {
  size_t struct_size;
  /* Distances beyond this are not measured (the answer is then "farther", cheap in free
     space); >= 0, in the model's unit; default INFINITY (any distance is measured). */
  double max_distance;
} tetrapage_distance_args;

/* Sets struct_size and the default above. A null args is ignored. */
void tetrapage_distance_args_init(tetrapage_distance_args* args);

/* The distance from the object at a pose to the environment. */
typedef struct tetrapage_distance_result {
  /* 0 touching (distance 0: surfaces meet, or one body holds the other: see containment),
     1 apart, 2 farther than max_distance (not measured; lower_bound >= max_distance). */
  int32_t separation;
  double distance;
  /* The true distance lies in [lower_bound, upper_bound] (the double computation's error
     bound); upper_bound is +infinity when farther. */
  double lower_bound;
  double upper_bound;
  double on_environment[3]; /* the closest points (apart), or a shared point (touching) */
  double on_object[3];
  /* The closest pair (environment_component TETRAPAGE_NO_COMPONENT); both triangles
     TETRAPAGE_NO_TRIANGLE / TETRAPAGE_NO_OBJECT_TRIANGLE when farther or a containment. */
  tetrapage_hit closest;
  int32_t containment; /* as tetrapage_query_info.containment */
  uint32_t containing_part;
  uint32_t containing_dynamic_part; /* the dynamic obstacle holding or held, else 0 */
  uint64_t pair_tests;              /* triangle pairs measured */
} tetrapage_distance_result;

/* Places the object at `pose` (as tetrapage_collide) and measures its distance to the
   environment: exact touching decision first, then closest points within max_distance.
   Consecutive poses of one object start from the last closest pair. This is a query: it
   replaces the object's last contacts.
   Errors: as tetrapage_collide; TETRAPAGE_ERROR_INPUT for a negative or NaN max_distance. */
tetrapage_status tetrapage_measure_distance(tetrapage_object* object, const double pose[7],
                                            const tetrapage_distance_args* args,
                                            tetrapage_distance_result* result);

/* ---- Time of impact ---- */

typedef struct tetrapage_impact_args {
  size_t struct_size;
  double tolerance;        /* the bracket's width at most, in (0, 1] of the motion's time;
                              default 1e-4 */
  uint64_t max_iterations; /* distance queries at most, in [1, 2^32 - 1]; default 10,000 */
} tetrapage_impact_args;

/* Sets struct_size and the defaults above. A null args is ignored. */
void tetrapage_impact_args_init(tetrapage_impact_args* args);

/* The first contact of the object moving from pose `from` to pose `to`. */
typedef struct tetrapage_impact_result {
  /* 0 none (certified: no contact during the motion), 1 hit, 2 unresolved (the iterations ran
     out: no contact before free_until, nothing known after). */
  int32_t impact;
  double free_until; /* no contact at any time in [0, free_until) */
  double contact_at; /* a hit: this pose touches; contact_at - free_until <= tolerance */
  /* A hit's first contact (environment_component TETRAPAGE_NO_COMPONENT); no triangles when
     there is none (no hit, or a hit by containment). */
  tetrapage_hit first_contact;
  int32_t containment; /* a hit by containment: as tetrapage_query_info.containment */
  uint32_t containing_part;
  uint32_t containing_dynamic_part;
  uint32_t iterations; /* distance queries run */
} tetrapage_impact_result;

/* The time of impact over the motion from `from` to `to` (translation linear, rotation by
   slerp over time [0, 1]) by conservative advancement, with a bracket of width `tolerance`
   closed by an exact collision query.
   Errors: as tetrapage_collide; TETRAPAGE_ERROR_INPUT for a tolerance outside (0, 1] or a
           max_iterations outside [1, 2^32 - 1]. */
tetrapage_status tetrapage_find_impact(tetrapage_object* object, const double from[7],
                                       const double to[7], const tetrapage_impact_args* args,
                                       tetrapage_impact_result* result);

/* ------------------------------------------------------------------------------------------ */
/* Groups of objects                                                                           */

/* Several objects moving through one index, checked at each step against the environment and
   against each other (the C++ ObjectGroup). Object/object answers are exact on the placed
   vertices: a pair collides when a triangle of one meets a triangle of the other (touching
   counts), or when one holds a component of the other inside a closed component. A group is
   used from one thread at a time. */
typedef struct tetrapage_group tetrapage_group;

/* Creates a group of `count` (>= 1) objects on `index`: the group's object k is a new flying
   instance of objects[k]'s mesh (the object handles stay the caller's; destroying them later
   does not affect the group). On failure *group is set to NULL.
   Errors: TETRAPAGE_ERROR_INPUT (count is 0), TETRAPAGE_ERROR_INVALID_ARGUMENT (a null
           argument or a null objects[k]), TETRAPAGE_ERROR_STALE_HANDLE (a closed index, or an
           objects[k] destroyed already). */
tetrapage_status tetrapage_group_create(tetrapage_index* index, tetrapage_object* const* objects,
                                        size_t count, tetrapage_group** group);

/* Releases the group, whose handle becomes stale. A null group is ignored (TETRAPAGE_OK).
   Errors: TETRAPAGE_ERROR_STALE_HANDLE (destroyed already, or not a group handle). */
tetrapage_status tetrapage_group_destroy(tetrapage_group* group);

/* One step: object k at poses[7k .. 7k+6] (tx, ty, tz, qw, qx, qy, qz, as tetrapage_collide),
   checked against the environment (exact accuracy, the object's mesh, discrete) and against
   every other object. all_contacts: 0 keeps the first contact found per object and per pair;
   non-zero every one. On success *colliding_pairs is the number of pairs of objects that
   collide; the answers are kept in the group until its next step.
   Errors: as tetrapage_collide (the message names the object of a bad pose),
           TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. After a failure the
           group holds no answer. */
tetrapage_status tetrapage_group_step(tetrapage_group* group, const double* poses, int all_contacts,
                                      size_t* colliding_pairs);

/* Copies the first min(capacity, count) colliding pairs of the last step to `pairs` as
   (first, second) object indices, first < second, sorted (2 * capacity uint32_t), and their
   number to *written. `pairs` may be null when capacity is 0.
   Errors: TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_group_pairs(const tetrapage_group* group, uint32_t* pairs, size_t capacity,
                                       size_t* written);

/* The triangle pairs of colliding pair `pair` (its rank in tetrapage_group_pairs): (triangle of
   first, triangle of second), sorted (2 * capacity uint32_t); *written is how many were copied
   and *containment why the pair collides without them: 0 surfaces touch, 1 first lies inside
   second, 2 second inside first (then no triangle pair). `triangles` may be null when capacity
   is 0; containment may be null.
   Errors: TETRAPAGE_ERROR_INPUT (no such pair), TETRAPAGE_ERROR_INVALID_ARGUMENT,
           TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_group_pair_triangles(const tetrapage_group* group, size_t pair,
                                                uint32_t* triangles, size_t capacity, size_t* written,
                                                int* containment);

/* Per object k, collides[k] = 1 when it collided with the environment in the last step (its
   surfaces touch, or one body holds the other), else 0; for the first min(capacity, count)
   objects, their number to *written.
   Errors: TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_group_environment(const tetrapage_group* group, int* collides, size_t capacity,
                                             size_t* written);

/* ---- Dynamic obstacles (DynamicObstacles.h) ----
   An overlay of parts inserted, moved and removed at run time on one index, and of index parts
   hidden from the answers. An object given the overlay (tetrapage_object_set_obstacles)
   answers as if the index held its visible parts plus the dynamic parts: a contact with a
   dynamic part is a tetrapage_hit with environment_part TETRAPAGE_DYNAMIC_PART,
   environment_triangle the triangle's index in that part's mesh, and dynamic_part its id.
   Changes from one thread, between the steps of the objects that hold the overlay. A pose is
   7 doubles (tx, ty, tz, qw, qx, qy, qz) as in tetrapage_collide. */
typedef struct tetrapage_obstacles tetrapage_obstacles;

/* An empty overlay on `index`.
   Errors: TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_obstacles_create(tetrapage_index* index,
                                            tetrapage_obstacles** obstacles);

/* Releases the overlay's handle (objects that hold it keep it until detached). A null one is
   ignored. Errors: TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_obstacles_destroy(tetrapage_obstacles* obstacles);

/* A new dynamic part: its mesh as in tetrapage_object_create, at `pose`, named `name` (may be
   null). Its id (never 0, never reused) goes to *id.
   Errors: TETRAPAGE_ERROR_INPUT (a mesh the object constructor rejects, a bad pose),
           TETRAPAGE_ERROR_INVALID_ARGUMENT,
           TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_obstacles_insert(tetrapage_obstacles* obstacles, const double* vertices,
                                            size_t vertex_count, const uint32_t* triangles,
                                            size_t triangle_count, const double pose[7],
                                            const char* name, uint32_t* id);

/* Moves or removes dynamic part `id`.
   Errors: TETRAPAGE_ERROR_INPUT (an unknown id, a bad pose), TETRAPAGE_ERROR_INVALID_ARGUMENT,
           TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_obstacles_move(tetrapage_obstacles* obstacles, uint32_t id,
                                          const double pose[7]);
tetrapage_status tetrapage_obstacles_remove(tetrapage_obstacles* obstacles, uint32_t id);

/* Hides part `part` of the index (hidden non-zero) or shows it again (0).
   Errors: TETRAPAGE_ERROR_INPUT (a part the index does not list), TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_obstacles_hide_part(tetrapage_obstacles* obstacles, uint32_t part,
                                               int hidden);

/* Merges the overlay into every later query of `object` (null obstacles: none again).
   Errors: TETRAPAGE_ERROR_INPUT (an overlay on another index), TETRAPAGE_ERROR_INVALID_ARGUMENT,
           TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_object_set_obstacles(tetrapage_object* object,
                                                tetrapage_obstacles* obstacles);

/* The same for every object of a group (their environment queries; null: none).
   Errors: TETRAPAGE_ERROR_INPUT (an overlay on another index), TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_group_set_obstacles(tetrapage_group* group,
                                               tetrapage_obstacles* obstacles);

/* Writes the overlay to `path`; reads one back on `index` (same ids, names, poses, meshes and
   hidden parts).
   Errors: TETRAPAGE_ERROR_IO (cannot write), TETRAPAGE_ERROR_FORMAT (a missing, truncated or
           malformed file, or one that does not fit the index; the message names the file),
           TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. */
tetrapage_status tetrapage_obstacles_save(const tetrapage_obstacles* obstacles, const char* path);
tetrapage_status tetrapage_obstacles_load(tetrapage_index* index, const char* path,
                                          tetrapage_obstacles** obstacles);

/* ------------------------------------------------------------------------------------------ */
/* Deprecated: the calls of the first release, thin wrappers over those above                   */
/* They stay for one release; compilers warn where they are used (TETRAPAGE_DEPRECATED). */

/* tetrapage_collide with the accuracy and parameter given, TETRAPAGE_SHAPE_MESH,
   TETRAPAGE_MOTION_DISCRETE, and all_contacts non-zero for TETRAPAGE_CONTACTS_ALL.
   Errors: as tetrapage_collide. */
TETRAPAGE_DEPRECATED("use tetrapage_collide")
tetrapage_status tetrapage_query(tetrapage_object* object, const double pose[7],
                                 tetrapage_accuracy accuracy, double parameter, int all_contacts,
                                 int* collides);

/* One contact: an environment triangle (its part, connected component and model-wide id) and
   an object triangle (UINT32_MAX when the object was checked as a solid). */
typedef struct tetrapage_contact {
  uint64_t environment_triangle;
  uint32_t environment_part;
  uint32_t object_triangle;
  uint32_t environment_component;
} tetrapage_contact;

/* Copies the first min(capacity, count) contacts of the last query to `contacts` and their
   number to *written. `contacts` may be null when capacity is 0.
   Errors: TETRAPAGE_ERROR_INVALID_ARGUMENT, TETRAPAGE_ERROR_STALE_HANDLE. */
TETRAPAGE_DEPRECATED("use tetrapage_get_hits")
tetrapage_status tetrapage_get_contacts(const tetrapage_object* object, tetrapage_contact* contacts,
                                        size_t capacity, size_t* written);

/* The distance from the object at a pose to the environment. */
typedef struct tetrapage_distance {
  /* 0 touching (distance 0: surfaces meet, or one body holds the other: see containment),
     1 apart, 2 farther than max_distance (not measured; lower_bound >= max_distance). */
  int separation;
  double distance;
  /* The true distance lies in [lower_bound, upper_bound] (the double computation's error
     bound); upper_bound is +infinity when farther. */
  double lower_bound;
  double upper_bound;
  double on_environment[3]; /* the closest points (apart), or a shared point (touching) */
  double on_object[3];
  uint64_t environment_triangle; /* UINT64_MAX when none (farther, or a containment) */
  uint32_t environment_part;
  uint32_t object_triangle;
  int containment; /* as tetrapage_query_info.containment */
  uint32_t containing_part;
  uint64_t pair_tests; /* triangle pairs measured */
} tetrapage_distance;

/* Places the object at `pose` (as tetrapage_collide) and measures its distance to the
   environment: exact touching decision first, then closest points within max_distance (pass
   INFINITY to measure any distance). Consecutive poses of one object start from the last
   closest pair. This is a query: it replaces the object's last contacts.
   Errors: as tetrapage_collide; TETRAPAGE_ERROR_INPUT for a negative or NaN max_distance. */
TETRAPAGE_DEPRECATED("use tetrapage_measure_distance")
tetrapage_status tetrapage_distance_query(tetrapage_object* object, const double pose[7],
                                          double max_distance, tetrapage_distance* result);

/* The first contact of the object moving from pose `from` to pose `to`. */
typedef struct tetrapage_impact {
  /* 0 none (certified: no contact during the motion), 1 hit, 2 unresolved (the iterations ran
     out: no contact before free_until, nothing known after). */
  int impact;
  double free_until; /* no contact at any time in [0, free_until) */
  double contact_at; /* a hit: this pose touches; contact_at - free_until <= tolerance */
  int has_contact;   /* the contact below is set (a hit by containment has none) */
  uint64_t environment_triangle;
  uint32_t environment_part;
  uint32_t object_triangle;
  uint32_t iterations; /* distance queries run */
} tetrapage_impact;

/* The time of impact over the motion from `from` to `to` (translation linear, rotation by
   slerp over time [0, 1]) by conservative advancement, with a bracket of width `tolerance`
   (in (0, 1]) closed by an exact collision query.
   Errors: as tetrapage_collide; TETRAPAGE_ERROR_INPUT for a tolerance outside (0, 1]. */
TETRAPAGE_DEPRECATED("use tetrapage_find_impact")
tetrapage_status tetrapage_time_of_impact(tetrapage_object* object, const double from[7],
                                          const double to[7], double tolerance,
                                          tetrapage_impact* result);

#ifdef __cplusplus
}
#endif

#endif /* TETRAPAGE_TETRAPAGE_H */
