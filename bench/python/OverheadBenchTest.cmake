# The Python overhead benchmark's harness on a tiny scene (ctest bench_python_overhead_harness):
#   cmake -DCLI= -DBENCH=tetrapage_bench_query_loop -DPYTHON= -DSCRIPT=overhead.py
#         -DMODULE_DIR=<build>/python -DWORK=folder -P OverheadBenchTest.cmake
# The script must run and print its three rows.

cmake_minimum_required(VERSION 3.22)

include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/RunChecked.cmake)

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
run_checked(${CLI} generate tetras --triangles 5000 --seed 5 -o ${WORK}/scene.ply)
run_checked(${CLI} preprocess ${WORK}/scene.ply -o ${WORK}/scene.tpi --region-triangles 400)
run_checked(${CLI} generate object --triangles 300 -o ${WORK}/object.ply)
run_checked(${CLI} generate flight --env ${WORK}/scene.ply --object ${WORK}/object.ply --steps 300 --seed 5
            -o ${WORK}/flight.csv)
run_checked(${CMAKE_COMMAND} -E env PYTHONPATH=${MODULE_DIR} ${PYTHON} ${SCRIPT} ${WORK}/scene.tpi
            ${WORK}/object.ply ${WORK}/flight.csv --cpp ${BENCH} --repeat 2)
message(STATUS "${last_output}")
foreach(row "| batch of 300: collides(poses) |" "| single pose: collides(pose) |"
            "| single pose: query(pose, all_contacts) |")
  string(FIND "${last_output}" "${row}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the table has no row '${row}'")
  endif()
endforeach()
