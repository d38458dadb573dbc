/* example.c - the tetrapage C API in one small program.
 *
 *   tetrapage_example_c INDEX.tpi OBJECT.ply [POSES.csv [ACCURACY]]
 *
 * Opens an index, loads a flying object, and queries a few poses: those of a pose file
 * (CSV `tx,ty,tz,qw,qx,qy,qz`), or by default five points along the diagonal of the model's
 * box. Prints the library's version (`tetrapage 0.1.0`), one line per pose (`pose K: collides`
 * or `pose K: free`) followed by up to five of its contacts, then a summary. Exits 1 with the
 * library's message on any error.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tetrapage/tetrapage.h"

enum { kMaxPoses = 100000, kShownContacts = 5 };

/* Reads a pose file into a new array of 7 doubles per pose; returns the count, -1 on error. */
static long read_poses(const char* path, double** poses) {
  FILE* file = fopen(path, "r");
  char line[512];
  long count = 0;
  *poses = NULL;
  if (!file) {
    fprintf(stderr, "error: cannot open the pose file %s\n", path);
    return -1;
  }
  if (!fgets(line, sizeof line, file) || strncmp(line, "tx,ty,tz,qw,qx,qy,qz", 20) != 0) {
    fprintf(stderr, "error: %s: the first line must be tx,ty,tz,qw,qx,qy,qz\n", path);
    fclose(file);
    return -1;
  }
  *poses = malloc(sizeof(double) * 7 * kMaxPoses);
  if (!*poses) {
    fclose(file);
    return -1;
  }
  while (count < kMaxPoses && fgets(line, sizeof line, file)) {
    double* p = *poses + 7 * count;
    if (line[0] == '\n' || line[0] == '\r' || line[0] == '\0') continue;
    if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf", &p[0], &p[1], &p[2], &p[3], &p[4], &p[5],
               &p[6]) != 7) {
      fprintf(stderr, "error: %s: line %ld is not a pose: %s", path, count + 2, line);
      free(*poses);
      *poses = NULL;
      fclose(file);
      return -1;
    }
    ++count;
  }
  fclose(file);
  return count;
}

/* Five poses on the diagonal of the model's box, turned by a growing angle about z. */
static long diagonal_poses(const tetrapage_index* index, double** poses) {
  double lo[3], hi[3];
  long k;
  if (tetrapage_index_bounds(index, lo, hi) != TETRAPAGE_OK) return -1;
  *poses = malloc(sizeof(double) * 7 * 5);
  if (!*poses) return -1;
  for (k = 0; k < 5; ++k) {
    const double f = 0.25 * (double)k, half_angle = 0.2 * (double)k;
    double* p = *poses + 7 * k;
    p[0] = lo[0] + f * (hi[0] - lo[0]);
    p[1] = lo[1] + f * (hi[1] - lo[1]);
    p[2] = lo[2] + f * (hi[2] - lo[2]);
    p[3] = cos(half_angle);
    p[4] = 0.0;
    p[5] = 0.0;
    p[6] = sin(half_angle);
  }
  return 5;
}

int main(int argc, char** argv) {
  tetrapage_index* index = NULL;
  tetrapage_object* object = NULL;
  tetrapage_accuracy accuracy = TETRAPAGE_ACCURACY_EXACT;
  double parameter = 0.0;
  tetrapage_query_args args;
  double* poses = NULL;
  long pose_count = 0, collisions = 0, k;
  int exit_code = 1;

  if (argc < 3 || argc > 5) {
    fprintf(stderr, "usage: %s INDEX.tpi OBJECT.ply [POSES.csv [ACCURACY]]\n", argv[0]);
    return 2;
  }
  if (argc == 5 && tetrapage_parse_accuracy(argv[4], &accuracy, &parameter) != TETRAPAGE_OK) {
    fprintf(stderr, "error: %s\n", tetrapage_last_error());
    return 2;
  }
  /* A shared library may come from another release than the headers this was compiled with. */
  printf("tetrapage %s\n", tetrapage_version());
  if (strcmp(tetrapage_version(), TETRAPAGE_VERSION_STRING) != 0)
    fprintf(stderr, "warning: compiled with tetrapage %s, running with %s\n",
            TETRAPAGE_VERSION_STRING, tetrapage_version());
  if (tetrapage_open(argv[1], TETRAPAGE_DEFAULT_BUDGET_BYTES, &index) != TETRAPAGE_OK ||
      tetrapage_object_create_from_file(index, argv[2], &object) != TETRAPAGE_OK) {
    fprintf(stderr, "error: %s\n", tetrapage_last_error());
    goto done;
  }
  pose_count = argc >= 4 ? read_poses(argv[3], &poses) : diagonal_poses(index, &poses);
  if (pose_count < 0) goto done;
  /* The options: the defaults, then what this program changes (every contact, the accuracy). */
  tetrapage_query_args_init(&args);
  args.accuracy = accuracy;
  args.parameter = parameter;
  args.contacts = TETRAPAGE_CONTACTS_ALL;

  for (k = 0; k < pose_count; ++k) {
    const double* pose = poses + 7 * k;
    tetrapage_hit contacts[kShownContacts];
    size_t count = 0, written = 0, c;
    int collides = 0;
    if (tetrapage_collide(object, pose, &args, &collides) != TETRAPAGE_OK ||
        tetrapage_contact_count(object, &count) != TETRAPAGE_OK ||
        tetrapage_get_hits(object, contacts, kShownContacts, &written) != TETRAPAGE_OK) {
      fprintf(stderr, "error: pose %ld: %s\n", k, tetrapage_last_error());
      goto done;
    }
    collisions += collides;
    printf("pose %ld: %s", k, collides ? "collides" : "free");
    if (collides) printf(", %zu contacts", count);
    printf("  (at %g %g %g)\n", pose[0], pose[1], pose[2]);
    for (c = 0; c < written; ++c) {
      char path[256];
      size_t length = 0;
      if (tetrapage_index_part_path(index, contacts[c].environment_part, path, sizeof path, &length) !=
          TETRAPAGE_OK) {
        fprintf(stderr, "error: pose %ld: %s\n", k, tetrapage_last_error());
        goto done;
      }
      printf("  environment part %u (%s) triangle %llu touches object triangle %u\n",
             (unsigned)contacts[c].environment_part, path,
             (unsigned long long)contacts[c].environment_triangle,
             (unsigned)contacts[c].object_triangle);
    }
    if (written < count) printf("  ... %zu more\n", count - written);
  }
  printf("collisions: %ld of %ld poses\n", collisions, pose_count);
  exit_code = 0;

done:
  free(poses);
  tetrapage_object_destroy(object);
  tetrapage_close(index);
  return exit_code;
}
