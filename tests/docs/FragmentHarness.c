/* The program around a ```c block of docs/USAGE.md marked <!-- fragment -->: the block runs in
   main() with `index` open on model.tpi, `object` made from tool.ply and check() (which stops
   the program with the library's message when a call fails) in scope; both are released after
   it. UsageBlocks.cmake puts the block where the marker line below stands. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "tetrapage/tetrapage.h"

static void check(tetrapage_status status) {
  if (status != TETRAPAGE_OK) {
    fprintf(stderr, "%s: %s\n", tetrapage_status_string(status), tetrapage_last_error());
    exit(1);
  }
}

int main(void) {
  tetrapage_index* index = NULL;
  tetrapage_object* object = NULL;
  check(tetrapage_open("model.tpi", TETRAPAGE_DEFAULT_BUDGET_BYTES, &index));
  check(tetrapage_object_create_from_file(index, "tool.ply", &object));
  {
@USAGE_BLOCK@
  }
  check(tetrapage_object_destroy(object));
  check(tetrapage_close(index));
  return 0;
}
