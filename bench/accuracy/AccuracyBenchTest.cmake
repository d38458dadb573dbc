# The accuracy benchmark's harness on a tiny generated scene (ctest bench_accuracy_harness):
#   cmake -DBENCH=tetrapage_bench_accuracy -DWORK=folder -P AccuracyBenchTest.cmake
# Every exact setting (shape x motion) on the double index must agree with the exact answer of
# its own question on every pose of both flights, and the grazing flight must graze.

cmake_minimum_required(VERSION 3.22)  # string(JSON)

include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/RunChecked.cmake)

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
run_checked(${BENCH} --tetras 20000 --object-triangles 300 --steps 600 --seed 3 --out ${WORK})
message(STATUS "${last_output}")

file(READ "${WORK}/accuracy.json" report)
string(JSON grazing_collisions GET "${report}" grazing_collisions)
if(grazing_collisions EQUAL 0)
  message(FATAL_ERROR "the grazing flight has no collision: it checks nothing")
endif()
string(JSON runs LENGTH "${report}" runs)
math(EXPR last "${runs} - 1")
set(checked 0)
foreach(i RANGE ${last})
  string(JSON accuracy GET "${report}" runs ${i} accuracy)
  string(JSON storage GET "${report}" runs ${i} storage)
  if(NOT accuracy STREQUAL "exact" OR NOT storage STREQUAL "double")
    continue()
  endif()
  string(JSON flight GET "${report}" runs ${i} flight)
  string(JSON shape GET "${report}" runs ${i} shape)
  string(JSON motion GET "${report}" runs ${i} motion)
  string(JSON fn GET "${report}" runs ${i} same_question false_negatives)
  string(JSON fp GET "${report}" runs ${i} same_question false_positives)
  if(NOT fn EQUAL 0 OR NOT fp EQUAL 0)
    message(FATAL_ERROR "exact ${shape} ${motion} on the ${flight} flight disagrees with its exact oracle: "
                        "${fn} false negatives, ${fp} false positives")
  endif()
  math(EXPR checked "${checked} + 1")
endforeach()
if(NOT checked EQUAL 12)
  message(FATAL_ERROR "expected 12 exact double runs (2 flights x 3 shapes x 2 motions), found ${checked}")
endif()
message(STATUS "${checked} exact settings agree with their oracles on every pose")
