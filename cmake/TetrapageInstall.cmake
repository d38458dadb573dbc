# The examples of the C and C++ APIs, and what `cmake --install` puts in a prefix so that
# another project can link tetrapage with `find_package(tetrapage)`: tetrapage::c, the C API in
# libtetrapage.so; tetrapage::runtime, the C++ API.
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
install(DIRECTORY ${PROJECT_SOURCE_DIR}/formats/include/ ${PROJECT_SOURCE_DIR}/runtime/include/
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
  # Installs the whole build tree into a temporary prefix: it needs every installed target built.
  # The consumer links the installed static libraries with the build type's linker flags (a
  # sanitizer build's libraries need its runtime).
  string(TOUPPER "${CMAKE_BUILD_TYPE}" build_type)
  add_test(NAME capi_install
    COMMAND ${CMAKE_COMMAND} -DBUILD_DIR=${PROJECT_BINARY_DIR}
            -DWORK=${PROJECT_BINARY_DIR}/tests/runtime/tmp/capi-install
            -DCONSUMER=${capi_tests_source}/install_consumer -DINDEX=${capi_work}/environment.tpi
            -DGENERATOR=${CMAKE_GENERATOR} -DC_COMPILER=${CMAKE_C_COMPILER}
            -DCXX_COMPILER=${CMAKE_CXX_COMPILER} "-DLINKER_FLAGS=${CMAKE_EXE_LINKER_FLAGS_${build_type}}"
            -P ${capi_tests_source}/CApiInstall.cmake)
  set_tests_properties(capi_install PROPERTIES FIXTURES_REQUIRED capi_index LABELS install TIMEOUT 600)
endif()
