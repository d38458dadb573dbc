# The examples of the C and C++ APIs, and what `cmake --install` puts in a prefix so that
# another project can link tetrapage: with `find_package(tetrapage)` (tetrapage::c, the C API in
# libtetrapage.so; tetrapage::runtime, the C++ API) or with pkg-config (tetrapage.pc,
# tetrapage-cpp.pc).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# --- Examples (runtime/examples) ---------------------------------------------------------------
add_executable(tetrapage_example_c ${PROJECT_SOURCE_DIR}/runtime/examples/example.c)
set_target_properties(tetrapage_example_c PROPERTIES C_STANDARD 11 C_STANDARD_REQUIRED ON
                                                     C_EXTENSIONS OFF)
# The shared C library, as a C program outside the tree links it: with the C driver, naming
# neither the C++ runtime nor tetrapage's dependencies (m: the example's own cos and sin).
target_link_libraries(tetrapage_example_c PRIVATE tetrapage::c m)
# tetrapage::warnings holds C++-only flags; the C example gets the C subset.
target_compile_options(tetrapage_example_c PRIVATE -Wall -Wextra -Wpedantic -Wshadow
                       $<$<BOOL:${TETRAPAGE_WERROR}>:-Werror>)

add_executable(tetrapage_example_cpp ${PROJECT_SOURCE_DIR}/runtime/examples/example.cpp)
target_link_libraries(tetrapage_example_cpp PRIVATE tetrapage::runtime tetrapage::warnings)

# --- Install --------------------------------------------------------------------------------
set(TETRAPAGE_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/tetrapage" CACHE STRING
    "Where the package configuration files go, relative to the install prefix")
set(TETRAPAGE_INSTALL_PKGCONFIGDIR "${CMAKE_INSTALL_LIBDIR}/pkgconfig" CACHE STRING
    "Where the pkg-config files go, relative to the install prefix")

# Consumers see tetrapage::c, tetrapage::formats and tetrapage::runtime, the names the build
# tree uses.
set_target_properties(tetrapage_c PROPERTIES EXPORT_NAME c)
set_target_properties(tetrapage_formats PROPERTIES EXPORT_NAME formats)
set_target_properties(tetrapage_runtime PROPERTIES EXPORT_NAME runtime)
# Static libraries carry their private links as $<LINK_ONLY:...> entries, so the export needs
# every target they name: tetrapage::warnings (an interface target whose compile flags never
# reach a consumer through LINK_ONLY) and the imported targets the config file finds again.
set_target_properties(tetrapage_warnings PROPERTIES EXPORT_NAME warnings)

install(TARGETS tetrapage_formats tetrapage_runtime tetrapage_warnings
        EXPORT tetrapageTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
# The shared C library has its own export set: it needs none of the packages the static
# libraries need, so that a project in C alone finds it without C++ or those packages.
install(TARGETS tetrapage_c
        EXPORT tetrapageCTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/formats/base/include/ ${PROJECT_SOURCE_DIR}/formats/mesh/include/
                  ${PROJECT_SOURCE_DIR}/formats/index/include/ ${PROJECT_SOURCE_DIR}/runtime/geometry/include/
                  ${PROJECT_SOURCE_DIR}/runtime/paging/include/ ${PROJECT_SOURCE_DIR}/runtime/query/include/
                  ${PROJECT_SOURCE_DIR}/runtime/capi/include/
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.h")
install(FILES ${TETRAPAGE_VERSION_HEADER} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/tetrapage)
install(TARGETS tetrapage RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

install(EXPORT tetrapageTargets
        NAMESPACE tetrapage::
        DESTINATION ${TETRAPAGE_INSTALL_CMAKEDIR})
install(EXPORT tetrapageCTargets
        NAMESPACE tetrapage::
        DESTINATION ${TETRAPAGE_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/tetrapageConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/tetrapageConfig.cmake
                              INSTALL_DESTINATION ${TETRAPAGE_INSTALL_CMAKEDIR})
# Before 1.0 a minor version may change the API.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/tetrapageConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/tetrapageConfig.cmake
              ${PROJECT_BINARY_DIR}/tetrapageConfigVersion.cmake
        DESTINATION ${TETRAPAGE_INSTALL_CMAKEDIR})

# --- pkg-config -------------------------------------------------------------------------------
# The prefix is found from the .pc file's own place (${pcfiledir}), so that a tree installed
# with `cmake --install --prefix P` (or moved after) describes itself; absolute install
# directories are written as they are.
foreach(dir LIBDIR INCLUDEDIR)
  if(IS_ABSOLUTE "${CMAKE_INSTALL_${dir}}")
    set(TETRAPAGE_PC_${dir} "${CMAKE_INSTALL_${dir}}")
  else()
    set(TETRAPAGE_PC_${dir} "\${prefix}/${CMAKE_INSTALL_${dir}}")
  endif()
endforeach()
if(IS_ABSOLUTE "${TETRAPAGE_INSTALL_PKGCONFIGDIR}")
  set(TETRAPAGE_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
else()
  file(RELATIVE_PATH pc_up "/prefix/${TETRAPAGE_INSTALL_PKGCONFIGDIR}" "/prefix")
  string(REGEX REPLACE "/$" "" pc_up "${pc_up}")
  set(TETRAPAGE_PC_PREFIX "\${pcfiledir}/${pc_up}")
endif()

# tetrapage_pc_link_flags(OUT ITEM...): the link flags of pkg-config's Libs for library files
# and imported targets: "-lNAME", preceded by "-LDIR" when the linker does not search DIR
# already; flags (-pthread) as they are.
function(tetrapage_pc_link_flags out)
  set(flags "")
  foreach(item IN LISTS ARGN)
    if(TARGET ${item})
      get_target_property(item ${item} LOCATION)
    endif()
    if(item MATCHES "^(.*)/lib([^/]+)\\.(so|a)(\\.[0-9.]+)?$")
      if(NOT CMAKE_MATCH_1 IN_LIST CMAKE_CXX_IMPLICIT_LINK_DIRECTORIES)
        list(APPEND flags "-L${CMAKE_MATCH_1}")
      endif()
      list(APPEND flags "-l${CMAKE_MATCH_2}")
    elseif(NOT item STREQUAL "")
      list(APPEND flags "${item}")
    endif()
  endforeach()
  list(REMOVE_DUPLICATES flags)
  list(JOIN flags " " flags)
  set(${out} "${flags}" PARENT_SCOPE)
endfunction()

# What the static libraries call outside themselves, for C++ programs that link them: HDF5's
# own library (its shared library brings what it needs; the compiler wrapper's list is for
# static HDF5 links), TBB, liblz4, GMP (CGAL's exact number types), MPFR, which CGAL's target
# links with it, and libdl (the CAD module, with OpenCASCADE and Assimp, is loaded at run time). Cflags: tetrapage's public headers
# include the standard library only.
set(hdf5_library "${HDF5_C_LIBRARIES}")
list(FILTER hdf5_library INCLUDE REGEX "/libhdf5[^/]*\\.(so|a)")
list(FILTER hdf5_library EXCLUDE REGEX "/libhdf5_hl[^/]*$")
if(NOT hdf5_library)
  set(hdf5_library "${HDF5_C_LIBRARIES}")
endif()
set(dl_flag "")
if(CMAKE_DL_LIBS)
  set(dl_flag "-l${CMAKE_DL_LIBS}")
endif()
tetrapage_pc_link_flags(TETRAPAGE_PC_CXX_DEPENDENCIES ${hdf5_library} TBB::tbb ${LZ4_LIBRARY}
                        ${MPFR_LIBRARIES} ${GMP_LIBRARIES} ${CMAKE_THREAD_LIBS_INIT} ${dl_flag})
foreach(pc tetrapage tetrapage-cpp)
  configure_file(${PROJECT_SOURCE_DIR}/cmake/${pc}.pc.in ${PROJECT_BINARY_DIR}/pkgconfig/${pc}.pc @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/pkgconfig/${pc}.pc DESTINATION ${TETRAPAGE_INSTALL_PKGCONFIGDIR})
endforeach()

# --- Tests of the examples and of the installed package ----------------------------------------
# Registered here, after the example targets exist (tests/ is configured before this file runs).
if(TETRAPAGE_BUILD_TESTS AND NOT TEST capi_example)
  set(capi_tests_source "${PROJECT_SOURCE_DIR}/tests/runtime")
  set(capi_work "${PROJECT_BINARY_DIR}/tests/runtime/tmp/capi-example")
  add_test(NAME capi_example_index
    COMMAND ${CMAKE_COMMAND} -DSTEP=index -DCLI=$<TARGET_FILE:tetrapage> -DWORK=${capi_work}
            -P ${capi_tests_source}/CApiExample.cmake)
  set_tests_properties(capi_example_index PROPERTIES FIXTURES_SETUP capi_index TIMEOUT 300)
  add_test(NAME capi_example
    COMMAND ${CMAKE_COMMAND} -DSTEP=run -DWORK=${capi_work} -DVERSION=${PROJECT_VERSION}
            -DEXAMPLES=$<TARGET_FILE:tetrapage_example_c>,$<TARGET_FILE:tetrapage_example_cpp>
            -P ${capi_tests_source}/CApiExample.cmake)
  set_tests_properties(capi_example PROPERTIES FIXTURES_REQUIRED capi_index TIMEOUT 300)
  # One install of the whole build tree into a temporary prefix (it needs every installed target
  # built), then four projects outside the tree build the examples against it: C and C++, with
  # find_package and with pkg-config. They link with the build type's linker flags (a sanitizer
  # build's libraries need its runtime).
  set(install_work "${PROJECT_BINARY_DIR}/tests/runtime/tmp/install")
  add_test(NAME install_prefix
    COMMAND ${CMAKE_COMMAND} -DSTEP=prefix -DBUILD_DIR=${PROJECT_BINARY_DIR}
            -DPREFIX=${install_work}/prefix -DLIBDIR=${CMAKE_INSTALL_LIBDIR} -DNM=${CMAKE_NM}
            -DHEADER=${PROJECT_SOURCE_DIR}/runtime/capi/include/tetrapage/tetrapage.h
            -P ${capi_tests_source}/Install.cmake)
  set_tests_properties(install_prefix PROPERTIES FIXTURES_SETUP tetrapage_prefix LABELS install
                                                 TIMEOUT 300)
  string(TOUPPER "${CMAKE_BUILD_TYPE}" build_type)
  foreach(language c cpp)
    foreach(method find_package pkg_config)
      add_test(NAME install_${language}_${method}
        COMMAND ${CMAKE_COMMAND} -DSTEP=consumer -DLANGUAGE=${language} -DMETHOD=${method}
                -DPREFIX=${install_work}/prefix -DLIBDIR=${CMAKE_INSTALL_LIBDIR}
                -DWORK=${install_work}/${language}-${method}
                -DCONSUMER=${capi_tests_source}/install_consumer
                -DEXAMPLES_DIR=${PROJECT_SOURCE_DIR}/runtime/examples
                -DUSAGE=${PROJECT_SOURCE_DIR}/docs/USAGE.md -DINDEX_WORK=${capi_work}
                -DVERSION=${PROJECT_VERSION} -DGENERATOR=${CMAKE_GENERATOR}
                -DC_COMPILER=${CMAKE_C_COMPILER} -DCXX_COMPILER=${CMAKE_CXX_COMPILER}
                "-DLINKER_FLAGS=${CMAKE_EXE_LINKER_FLAGS_${build_type}}"
                -P ${capi_tests_source}/Install.cmake)
      set_tests_properties(install_${language}_${method} PROPERTIES
                           FIXTURES_REQUIRED "tetrapage_prefix;capi_index" LABELS install TIMEOUT 600)
    endforeach()
  endforeach()
endif()
