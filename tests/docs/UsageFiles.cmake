# The files docs/USAGE.md's examples open, in WORK: model.tpi (the C API examples' index:
# tests/runtime/CApiExample.cmake, tetrahedra in the unit cube, one part each), its flight
# flight.csv with the oracle's answers.csv, and three flying objects fitted to a 0.05 cube:
# tool.ply (a 200-triangle sphere), part.ply (a tetrahedron) and crate.ply (a 116-triangle sphere).
#   -DCLI=tetrapage -DWORK=folder -DCAPI_EXAMPLE=tests/runtime/CApiExample.cmake

include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/RunChecked.cmake)

run_checked(${CMAKE_COMMAND} -DSTEP=index -DCLI=${CLI} -DWORK=${WORK}/index -P ${CAPI_EXAMPLE})
file(COPY_FILE ${WORK}/index/environment.tpi ${WORK}/model.tpi)
file(COPY_FILE ${WORK}/index/flight.csv ${WORK}/flight.csv)
file(COPY_FILE ${WORK}/index/answers.csv ${WORK}/answers.csv)
run_checked(${CLI} mesh convert ${WORK}/index/object.obj -o ${WORK}/tool.ply)
run_checked(${CLI} generate object --triangles 4 -o ${WORK}/part.ply)
run_checked(${CLI} generate object --triangles 116 -o ${WORK}/crate.ply)
