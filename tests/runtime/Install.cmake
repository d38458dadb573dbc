# What `cmake --install` gives another project, tested as users link it: one install into a
# temporary prefix (STEP=prefix), then four projects outside the tree (STEP=consumer), each
# building a runtime example against the prefix and flying the capi_example fixture's flight
# with CApiExample.cmake's checks (answers equal the oracle's, the version printed).
#   STEP=prefix:   -DBUILD_DIR -DPREFIX -DLIBDIR (relative to PREFIX) -DNM -DHEADER (tetrapage.h)
#                  installs; checks the files, and that libtetrapage.so exports exactly the
#                  functions tetrapage.h declares.
#   STEP=consumer: -DLANGUAGE=c|cpp -DMETHOD=find_package|pkg_config -DPREFIX -DLIBDIR -DWORK
#                  -DCONSUMER (tests/runtime/install_consumer) -DEXAMPLES_DIR (runtime/examples)
#                  -DUSAGE (docs/USAGE.md) -DINDEX_WORK (the fixture's folder) -DVERSION
#                  -DGENERATOR -DC_COMPILER -DCXX_COMPILER -DLINKER_FLAGS (the build type's,
#                  e.g. the sanitizers' runtimes)
# USAGE.md shows these projects' CMakeLists.txt and pkg-config commands: the consumer step
# requires them there word for word, so that the documentation is what this test builds.

include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/RunChecked.cmake)

if(STEP STREQUAL "prefix")
  file(REMOVE_RECURSE "${PREFIX}")
  run_checked(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${PREFIX})
  foreach(installed ${LIBDIR}/cmake/tetrapage/tetrapageConfig.cmake
                    ${LIBDIR}/cmake/tetrapage/tetrapageConfigVersion.cmake
                    ${LIBDIR}/cmake/tetrapage/tetrapageTargets.cmake
                    ${LIBDIR}/cmake/tetrapage/tetrapageCTargets.cmake
                    ${LIBDIR}/pkgconfig/tetrapage.pc ${LIBDIR}/pkgconfig/tetrapage-cpp.pc
                    ${LIBDIR}/libtetrapage.so ${LIBDIR}/libtetrapage_runtime.a
                    ${LIBDIR}/libtetrapage_formats.a ${LIBDIR}/tetrapage/tetrapage_cad.so
                    include/tetrapage/tetrapage.h include/tetrapage/version.h
                    include/tetrapage/runtime/query/FlyingObject.h include/tetrapage/formats/base/Error.h
                    bin/tetrapage)
    if(NOT EXISTS "${PREFIX}/${installed}")
      message(FATAL_ERROR "not installed: ${PREFIX}/${installed}")
    endif()
  endforeach()

  # The C API and nothing else: a missing function fails C programs at link time, an extra
  # symbol (C++ code linked in) could clash with a program's own.
  file(STRINGS "${HEADER}" declarations REGEX "^[a-z][a-z_ *]*[ *]tetrapage_[a-z0-9_]+\\(")
  set(declared "")
  foreach(line IN LISTS declarations)
    string(REGEX MATCH "tetrapage_[a-z0-9_]+\\(" name "${line}")
    string(REPLACE "(" "" name "${name}")
    list(APPEND declared ${name})
  endforeach()
  run_checked(${NM} -D --defined-only ${PREFIX}/${LIBDIR}/libtetrapage.so)
  string(REGEX MATCHALL "[^\n]+" symbol_lines "${last_output}")
  set(exported "")
  foreach(line IN LISTS symbol_lines)
    string(REGEX REPLACE ".* " "" name "${line}")
    list(APPEND exported ${name})
  endforeach()
  list(SORT declared)
  list(SORT exported)
  if(NOT declared STREQUAL exported OR declared STREQUAL "")
    message(FATAL_ERROR "libtetrapage.so exports\n  ${exported}\ntetrapage.h declares\n  ${declared}")
  endif()
  list(LENGTH exported count)
  message(STATUS "installed into ${PREFIX}; libtetrapage.so exports the ${count} functions of tetrapage.h")
  return()
endif()

if(NOT STEP STREQUAL "consumer")
  message(FATAL_ERROR "STEP must be prefix or consumer, not '${STEP}'")
endif()

file(READ "${USAGE}" usage)
set(source "${WORK}/src")
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${source}")
if(LANGUAGE STREQUAL "c")
  set(example example.c)
  set(program viewer.c)
else()
  set(example example.cpp)
  set(program viewer.cpp)
endif()
configure_file(${EXAMPLES_DIR}/${example} ${source}/${program} COPYONLY)

if(METHOD STREQUAL "find_package")
  file(READ "${CONSUMER}/${LANGUAGE}/CMakeLists.txt" project_text)
  string(FIND "${usage}" "${project_text}" at)
  if(at LESS 0)
    message(FATAL_ERROR "docs/USAGE.md does not show ${CONSUMER}/${LANGUAGE}/CMakeLists.txt as it is:\n${project_text}")
  endif()
  configure_file(${CONSUMER}/${LANGUAGE}/CMakeLists.txt ${source}/CMakeLists.txt COPYONLY)
  run_checked(${CMAKE_COMMAND} -S ${source} -B ${WORK}/build -G ${GENERATOR}
              -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=${C_COMPILER}
              -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_PREFIX_PATH=${PREFIX}
              "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}")
  run_checked(${CMAKE_COMMAND} --build ${WORK}/build)
  set(built ${WORK}/build/viewer)
  # CMake's build RPATH finds libtetrapage.so: no LD_LIBRARY_PATH.
  set(environment "")
elseif(METHOD STREQUAL "pkg_config")
  if(LANGUAGE STREQUAL "c")
    set(command "cc viewer.c $(pkg-config --cflags --libs tetrapage) -lm -o viewer")
    set(compiler ${C_COMPILER})
  else()
    set(command "c++ -std=c++20 viewer.cpp $(pkg-config --cflags --libs tetrapage-cpp) -o viewer")
    set(compiler ${CXX_COMPILER})
  endif()
  string(FIND "${usage}" "${command}" at)
  if(at LESS 0)
    message(FATAL_ERROR "docs/USAGE.md does not show the command `${command}`")
  endif()
  string(REGEX REPLACE "^(cc|c\\+\\+) " "${compiler} " command "${command} ${LINKER_FLAGS}")
  run_checked(${CMAKE_COMMAND} -E env PKG_CONFIG_PATH=${PREFIX}/${LIBDIR}/pkgconfig
              sh -c "cd ${source} && ${command}")
  set(built ${source}/viewer)
  # A prefix the loader does not search: the shared library is found as USAGE.md says.
  set(environment LD_LIBRARY_PATH=${PREFIX}/${LIBDIR})
else()
  message(FATAL_ERROR "METHOD must be find_package or pkg_config, not '${METHOD}'")
endif()

run_checked(${CMAKE_COMMAND} -E env ${environment} ${CMAKE_COMMAND} -DSTEP=run -DWORK=${INDEX_WORK}
            -DEXAMPLES=${built} -DVERSION=${VERSION}
            -P ${CMAKE_CURRENT_LIST_DIR}/CApiExample.cmake)
message(STATUS "${last_output}")
