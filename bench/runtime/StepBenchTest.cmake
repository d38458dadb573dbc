# The step benchmark's harness on a tiny generated scene (ctest bench_steps_harness):
#   cmake -DCLI=tetrapage -DBENCH=tetrapage_bench_steps -DWORK=folder -P StepBenchTest.cmake
# A billiard flight through random tetrahedra with the oracle's answers, replayed twice: every
# answer must agree, some must be collisions, and the tables must have a row for every kind of
# step, and the phase table its columns.

cmake_minimum_required(VERSION 3.22)

include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/RunChecked.cmake)

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
run_checked(${CLI} generate tetras --triangles 20000 --seed 5 -o ${WORK}/scene.ply)
run_checked(${CLI} preprocess ${WORK}/scene.ply -o ${WORK}/scene.tpi --precision double --region-triangles 400)
run_checked(${CLI} generate object --triangles 500 -o ${WORK}/object.ply)
run_checked(${CLI} generate flight --env ${WORK}/scene.ply --object ${WORK}/object.ply --steps 600 --seed 5
            -o ${WORK}/flight.csv --answers ${WORK}/answers.csv)

run_checked(${BENCH} ${WORK}/scene.tpi ${WORK}/object.ply ${WORK}/flight.csv --answers ${WORK}/answers.csv --repeat 2)
message(STATUS "${last_output}")
if(NOT last_output MATCHES "1200 steps \\(2 passes of 600 poses\\)")
  message(FATAL_ERROR "the benchmark did not fly both passes")
endif()
if(NOT last_output MATCHES "disagreements with [^\n]*answers.csv: 0")
  message(FATAL_ERROR "the runtime's answers differ from the oracle's")
endif()
if(last_output MATCHES "\\| collides \\| 0.00 %")
  message(FATAL_ERROR "the flight must collide somewhere, or its answers test little")
endif()
foreach(row "| searched |" "| no candidate |" "| phase II |" "| candidates |" "| collides |" "| no shard |")
  string(FIND "${last_output}" "${row}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the table has no row '${row}'")
  endif()
endforeach()
foreach(table "mean us of each phase by kind of step" "| step | locate | search | free box |" "| candidates | repeats |")
  string(FIND "${last_output}" "${table}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "no phase table ('${table}')")
  endif()
endforeach()

