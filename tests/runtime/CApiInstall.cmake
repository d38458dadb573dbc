# Installs the build into a fresh prefix, then configures, builds and runs a consumer project
# that finds it with find_package(tetrapage) and calls the C API.
#   -DBUILD_DIR -DWORK -DCONSUMER (source folder) -DINDEX (an index to open) -DGENERATOR
#   -DC_COMPILER -DCXX_COMPILER -DLINKER_FLAGS (the build type's, e.g. the sanitizers' runtimes)

include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/RunChecked.cmake)

file(REMOVE_RECURSE "${WORK}")
set(prefix "${WORK}/prefix")
run_checked(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(installed lib/cmake/tetrapage/tetrapageConfig.cmake lib/cmake/tetrapage/tetrapageConfigVersion.cmake
                  include/tetrapage/tetrapage.h include/tetrapage/runtime/FlyingObject.h
                  include/tetrapage/formats/Error.h bin/tetrapage)
  if(NOT EXISTS "${prefix}/${installed}")
    message(FATAL_ERROR "not installed: ${prefix}/${installed}")
  endif()
endforeach()

run_checked(${CMAKE_COMMAND} -S ${CONSUMER} -B ${WORK}/consumer-build -G ${GENERATOR}
            -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=${C_COMPILER} -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
            -DCMAKE_PREFIX_PATH=${prefix} "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}")
run_checked(${CMAKE_COMMAND} --build ${WORK}/consumer-build)
run_checked(${WORK}/consumer-build/consumer ${INDEX})
message(STATUS "${last_output}")
