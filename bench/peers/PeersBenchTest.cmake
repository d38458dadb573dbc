# The peer benchmark's harness on a tiny generated scene (ctest bench_peers_harness):
#   cmake -DCLI=tetrapage -DBENCH=tetrapage_bench_peers -DWORK=folder -P PeersBenchTest.cmake
# Every collider replays a billiard flight and must agree on every pose with the exact answer to
# its own question (FCL with CGAL's exact surface test; tetrapage with the oracle's answer
# file); a surfaces-only collider may differ from the oracle only where the object lies inside
# an obstacle without touching it, and must differ there.

cmake_minimum_required(VERSION 3.22)  # string(JSON), if(IN_LIST)

include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/RunChecked.cmake)

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
# Tetras: dense enough that a short billiard flight collides a few dozen times.
run_checked(${CLI} generate tetras --triangles 20000 --seed 3 -o ${WORK}/scene.ply)
run_checked(${CLI} generate object --triangles 300 -o ${WORK}/object.ply)
run_checked(${CLI} generate flight --env ${WORK}/scene.ply --object ${WORK}/object.ply --steps 1000 --seed 1
            -o ${WORK}/flight.csv --answers ${WORK}/answers.csv)
# Stored in double: the index holds the oracle's coordinates exactly.
run_checked(${CLI} preprocess ${WORK}/scene.ply -o ${WORK}/scene.tpi --precision double --threads 1)
run_checked(${BENCH} ${WORK}/scene.ply ${WORK}/object.ply ${WORK}/flight.csv ${WORK}/answers.csv ${WORK}/scene.tpi
            --memory 1M --report ${WORK}/report.json)
message(STATUS "${last_output}")

file(STRINGS "${WORK}/answers.csv" answer_lines)
list(REMOVE_AT answer_lines 0)  # header step,collides
list(LENGTH answer_lines steps)
set(oracle_collisions 0)
foreach(line IN LISTS answer_lines)
  if(line MATCHES ",1$")
    math(EXPR oracle_collisions "${oracle_collisions} + 1")
  endif()
endforeach()
if(oracle_collisions EQUAL 0)
  message(FATAL_ERROR "the test flight has no collision: it checks nothing")
endif()

file(READ "${WORK}/report.json" report)
# The machine and every timed build are stated (issue 36: a figure is read against both).
string(JSON processor GET "${report}" machine processor)
string(JSON load GET "${report}" machine load_average_at_end)
string(JSON builds LENGTH "${report}" builds)
string(JSON own_flags GET "${report}" builds 0 flags)
if(processor STREQUAL "" OR load STREQUAL "" OR builds LESS 5 OR own_flags STREQUAL "")
  message(FATAL_ERROR "the report does not state the machine and the builds: ${processor}, ${load}, ${builds}")
endif()
string(JSON inside_only GET "${report}" inside_only_poses)
string(JSON runs LENGTH "${report}" runs)
set(seen "")
math(EXPR last "${runs} - 1")
foreach(i RANGE ${last})
  string(JSON name GET "${report}" runs ${i} collider)
  string(JSON question GET "${report}" runs ${i} question)
  string(JSON run_steps GET "${report}" runs ${i} steps)
  list(APPEND seen ${name})
  if(NOT run_steps EQUAL steps)
    message(FATAL_ERROR "${name} answered ${run_steps} poses of ${steps}")
  endif()
  foreach(key same_question oracle)
    string(JSON fn_${key} GET "${report}" runs ${i} disagreements ${key} false_negatives)
    string(JSON fp_${key} GET "${report}" runs ${i} disagreements ${key} false_positives)
  endforeach()
  if(NOT fn_same_question EQUAL 0 OR NOT fp_same_question EQUAL 0)
    message(FATAL_ERROR "${name} disagrees with the exact answer to its question (${question}): "
                        "${fn_same_question} false negatives, ${fp_same_question} false positives")
  endif()
  set(expected_fn 0)
  if(question STREQUAL "surfaces")
    set(expected_fn ${inside_only})
  endif()
  if(NOT fn_oracle EQUAL expected_fn OR NOT fp_oracle EQUAL 0)
    message(FATAL_ERROR "${name} (${question}) disagrees with the oracle on ${fn_oracle} / ${fp_oracle} poses "
                        "(FN / FP); only the ${expected_fn} poses with the object inside an obstacle are explained")
  endif()
  if(name MATCHES "^tetrapage")
    # The runtime's runs say how many shards a near step touched (issue 36 reads it).
    string(JSON near_shards GET "${report}" runs ${i} figures per_near_step shards_touched)
    if(NOT near_shards GREATER 0)
      message(FATAL_ERROR "${name} reports ${near_shards} shards a near step")
    endif()
  endif()
  if(name STREQUAL "cgal")
    string(JSON collisions GET "${report}" runs ${i} collisions)
    if(NOT collisions EQUAL oracle_collisions)
      message(FATAL_ERROR "the oracle run found ${collisions} collisions, its answer file ${oracle_collisions}")
    endif()
  endif()
endforeach()
foreach(expected fcl embree cgal-surfaces cgal tetrapage tetrapage-paged)
  if(NOT expected IN_LIST seen)
    message(FATAL_ERROR "no ${expected} run in the report (runs: ${seen})")
  endif()
endforeach()
message(STATUS "${runs} colliders, ${steps} poses, ${oracle_collisions} collisions, ${inside_only} inside only: all explained")
