# Runs one example of docs/USAGE.md in a fresh folder WORK holding copies of the files in FILES
# (UsageFiles.cmake): it must exit 0 and, when OUTPUT names a file, print something that
# matches the regular expression in it.
#   -DPROGRAM=example -DFILES=folder -DWORK=folder -DWHERE=USAGE.md:line [-DOUTPUT=file]

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
file(GLOB inputs "${FILES}/*.*")
file(COPY ${inputs} DESTINATION "${WORK}")
execute_process(COMMAND ${PROGRAM} WORKING_DIRECTORY "${WORK}" RESULT_VARIABLE result OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
message(STATUS "the example at ${WHERE} printed:\n${out}${err}")
if(NOT result EQUAL 0)
  message(FATAL_ERROR "the example at ${WHERE} exited with ${result}")
endif()
if(OUTPUT)
  file(READ "${OUTPUT}" expected)
  string(REPLACE "\\n" "\n" expected "${expected}")  # a line break written \n in the comment
  if(NOT out MATCHES "${expected}")
    message(FATAL_ERROR "the example at ${WHERE} does not print what its <!-- output: --> comment says: ${expected}")
  endif()
endif()
