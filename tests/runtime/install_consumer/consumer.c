/* consumer: opens an index with the installed C API; a missing file must be an I/O error.
   Usage: consumer INDEX.tpi (exit 0 when the index opens and the missing one does not). */
#include <stdio.h>
#include <string.h>

#include <tetrapage/tetrapage.h>

int main(int argc, char** argv) {
  tetrapage_index* index = NULL;
  double lo[3], hi[3];
  if (argc != 2) return 2;
  if (tetrapage_open("/nonexistent/missing.tpi", TETRAPAGE_DEFAULT_BUDGET_BYTES, &index) !=
          TETRAPAGE_ERROR_IO ||
      index != NULL || strstr(tetrapage_last_error(), "missing.tpi") == NULL) {
    fprintf(stderr, "a missing index was not reported as an I/O error: %s\n", tetrapage_last_error());
    return 1;
  }
  if (tetrapage_open(argv[1], TETRAPAGE_DEFAULT_BUDGET_BYTES, &index) != TETRAPAGE_OK ||
      tetrapage_index_bounds(index, lo, hi) != TETRAPAGE_OK) {
    fprintf(stderr, "error: %s\n", tetrapage_last_error());
    return 1;
  }
  printf("opened %s: bounds %g %g %g .. %g %g %g\n", argv[1], lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  tetrapage_close(index);
  return 0;
}
