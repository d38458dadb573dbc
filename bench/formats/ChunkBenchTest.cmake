# The chunk benchmark's harness on a tiny generated scene (ctest bench_chunks_harness):
#   cmake -DCLI=tetrapage -DBENCH=tetrapage_bench_chunks -DWORK=folder -P ChunkBenchTest.cmake
# The scene is preprocessed on one thread and on all: the two indexes must hold the same shards
# (the comparison the benchmark makes for preprocess changes), and a third index from another
# scene must not; the table must have every row. With --compression none the shards are the
# same, stored larger.

cmake_minimum_required(VERSION 3.22)

include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/RunChecked.cmake)

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
run_checked(${CLI} generate tetras --triangles 20000 --seed 3 -o ${WORK}/scene.ply)
run_checked(${CLI} generate tetras --triangles 20000 --seed 4 -o ${WORK}/other.ply)
run_checked(${CLI} preprocess ${WORK}/scene.ply -o ${WORK}/one.tpi --threads 1 --region-triangles 500)
run_checked(${CLI} preprocess ${WORK}/scene.ply -o ${WORK}/all.tpi --region-triangles 500)
run_checked(${CLI} preprocess ${WORK}/other.ply -o ${WORK}/other.tpi --region-triangles 500)

run_checked(${BENCH} ${WORK}/one.tpi --every 1 --same-shards ${WORK}/all.tpi)
message(STATUS "${last_output}")
if(NOT last_output MATCHES "same shards: 0 of [1-9][0-9]* differ")
  message(FATAL_ERROR "one thread and all threads wrote different shards, or none")
endif()
foreach(row "| 8 KiB | no | deflate 1 |" "| 16 KiB | yes | LZ4 |" "| 64 KiB | yes | deflate 4 |")
  string(FIND "${last_output}" "${row}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the table has no row '${row}'")
  endif()
endforeach()

execute_process(COMMAND ${BENCH} ${WORK}/one.tpi --same-shards ${WORK}/other.tpi
                RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(result EQUAL 0)
  message(FATAL_ERROR "another scene's index was reported the same:\n${out}")
endif()

run_checked(${CLI} preprocess ${WORK}/scene.ply -o ${WORK}/none.tpi --region-triangles 500 --compression none)
run_checked(${BENCH} ${WORK}/none.tpi --every 1 --same-shards ${WORK}/all.tpi)
if(NOT last_output MATCHES "same shards: 0 of [1-9][0-9]* differ")
  message(FATAL_ERROR "--compression none wrote other shards:\n${last_output}")
endif()
string(REGEX MATCH "mean payload ([0-9]+) B, stored ([0-9]+) B" sizes "${last_output}")
set(none_stored ${CMAKE_MATCH_2})
run_checked(${BENCH} ${WORK}/all.tpi --every 1)
string(REGEX MATCH "mean payload ([0-9]+) B, stored ([0-9]+) B" sizes "${last_output}")
if(NOT none_stored GREATER CMAKE_MATCH_2)
  message(FATAL_ERROR "uncompressed shards stored in ${none_stored} B, compressed in ${CMAKE_MATCH_2} B")
endif()
