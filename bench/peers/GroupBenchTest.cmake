# The group benchmark's harness (ctest bench_group_harness), tiny so that it cannot rot:
#   cmake -DBENCH=tetrapage_bench_group -DWORK=folder -P GroupBenchTest.cmake
# Both colliders must answer every step, and the walk must make contacts; FCL decides in floating
# point, so its disagreements with tetrapage's exact answer are reported, not required to be 0.

cmake_minimum_required(VERSION 3.22)  # string(JSON)

include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/RunChecked.cmake)

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
run_checked(${BENCH} --counts 2,8 --steps 60 --triangles 116 --repeats 1 --report ${WORK}/report.json)
message(STATUS "${last_output}")

file(READ "${WORK}/report.json" report)
string(JSON runs LENGTH "${report}" runs)
if(NOT runs EQUAL 2)
  message(FATAL_ERROR "expected 2 runs (2 and 8 objects), the report has ${runs}")
endif()
set(contacts 0)
foreach(i 0 1)
  string(JSON steps GET "${report}" runs ${i} steps)
  string(JSON pairs GET "${report}" runs ${i} colliding_pairs)
  string(JSON wrong GET "${report}" runs ${i} disagreeing_pairs)
  if(NOT steps EQUAL 60)
    message(FATAL_ERROR "run ${i} answered ${steps} steps of 60")
  endif()
  if(wrong GREATER pairs)
    message(FATAL_ERROR "run ${i}: FCL disagrees on ${wrong} pairs, more than the ${pairs} colliding ones")
  endif()
  math(EXPR contacts "${contacts} + ${pairs}")
endforeach()
if(contacts EQUAL 0)
  message(FATAL_ERROR "the random walk made no contact: the harness checks nothing")
endif()
