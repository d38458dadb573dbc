# The C and C++ examples (runtime/examples) on an index made by `tetrapage preprocess`, checked
# against the reference oracle of `tetrapage generate flight --answers`.
#   STEP=index: -DCLI=tetrapage -DWORK=folder   generates an environment, an object, a flight
#               with the oracle's answers, and the index (the fixture of the other tests).
#   STEP=run:   -DEXAMPLES=a,b -DWORK=folder    runs each example on the flight and requires its
#               answers to equal the oracle's; also the default poses and a missing index.
#               -DVERSION=x.y.z: each example's first line must be `tetrapage x.y.z`, with no
#               warning that the library and the headers differ.

include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/RunChecked.cmake)

if(STEP STREQUAL "index")
  file(REMOVE_RECURSE "${WORK}")
  file(MAKE_DIRECTORY "${WORK}")
  run_checked(${CLI} generate tetras --triangles 2000 --seed 5 -o ${WORK}/environment.obj)
  run_checked(${CLI} generate object --triangles 200 -o ${WORK}/object.obj)
  run_checked(${CLI} generate flight --env ${WORK}/environment.obj --object ${WORK}/object.obj
              --steps 300 --seed 5 -o ${WORK}/flight.csv --answers ${WORK}/answers.csv)
  # Stored in double: the index holds the oracle's coordinates exactly.
  run_checked(${CLI} preprocess ${WORK}/environment.obj -o ${WORK}/environment.tpi
              --precision double --threads 1 --region-triangles 200)
  return()
endif()

if(NOT STEP STREQUAL "run")
  message(FATAL_ERROR "STEP must be index or run, not '${STEP}'")
endif()

# The oracle's answers: one 0/1 per pose.
file(STRINGS "${WORK}/answers.csv" answer_lines)
list(REMOVE_AT answer_lines 0)  # header step,collides
set(expected "")
set(expected_collisions 0)
foreach(line IN LISTS answer_lines)
  if(line MATCHES "^([0-9]+),([01])")
    list(APPEND expected ${CMAKE_MATCH_2})
    math(EXPR expected_collisions "${expected_collisions} + ${CMAKE_MATCH_2}")
  endif()
endforeach()
list(LENGTH expected pose_count)
if(pose_count EQUAL 0 OR expected_collisions EQUAL 0 OR expected_collisions EQUAL pose_count)
  message(FATAL_ERROR "the fixture's flight has ${expected_collisions} collisions in ${pose_count} "
                      "poses: it must have both answers (change its seed)")
endif()

string(REPLACE "," ";" examples "${EXAMPLES}")
foreach(example IN LISTS examples)
  execute_process(COMMAND ${example} ${WORK}/environment.tpi ${WORK}/object.obj ${WORK}/flight.csv exact
                  RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "${example} failed (${result}):\n${err}")
  endif()
  if(DEFINED VERSION)
    string(REPLACE "." "\\." version_pattern "${VERSION}")
    if(NOT out MATCHES "^tetrapage ${version_pattern}\n" OR err MATCHES "compiled with")
      message(FATAL_ERROR "${example} does not begin with `tetrapage ${VERSION}`:\n${out}\n${err}")
    endif()
  endif()
  string(REGEX MATCHALL "pose [0-9]+: (collides|free)" answers "${out}")
  list(LENGTH answers answer_count)
  if(NOT answer_count EQUAL pose_count)
    message(FATAL_ERROR "${example} answered ${answer_count} poses, the flight has ${pose_count}:\n${out}")
  endif()
  set(disagreements 0)
  foreach(k RANGE 1 ${pose_count})
    math(EXPR i "${k} - 1")
    list(GET answers ${i} answer)
    list(GET expected ${i} oracle)
    set(mine 0)
    if(answer MATCHES "collides")
      set(mine 1)
      string(REGEX MATCH "pose ${i}: collides, [0-9]+ contacts[^\n]*\n  environment part" detail "${out}")
      if(detail STREQUAL "")
        message(FATAL_ERROR "${example}: pose ${i} collides but lists no contact:\n${out}")
      endif()
    endif()
    if(NOT mine EQUAL oracle)
      math(EXPR disagreements "${disagreements} + 1")
      message(SEND_ERROR "${example}: pose ${i}: ${answer}, the oracle says ${oracle}")
    endif()
  endforeach()
  if(NOT out MATCHES "collisions: ${expected_collisions} of ${pose_count} poses")
    message(FATAL_ERROR "${example}: wrong summary (oracle: ${expected_collisions} of ${pose_count}):\n${out}")
  endif()
  message(STATUS "${example}: ${pose_count} poses, ${expected_collisions} collisions, ${disagreements} disagreements")

  # The default poses (five on the model box's diagonal).
  execute_process(COMMAND ${example} ${WORK}/environment.tpi ${WORK}/object.obj
                  RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT result EQUAL 0 OR NOT out MATCHES "collisions: [0-5] of 5 poses")
    message(FATAL_ERROR "${example} with default poses (${result}):\n${out}\n${err}")
  endif()

  # A missing index: a non-zero exit and a message naming the file.
  execute_process(COMMAND ${example} ${WORK}/missing.tpi ${WORK}/object.obj
                  RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(result EQUAL 0 OR NOT err MATCHES "missing\\.tpi")
    message(FATAL_ERROR "${example} on a missing index: exit ${result}, stderr: ${err}")
  endif()
endforeach()
