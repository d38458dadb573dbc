# Warnings as an INTERFACE target that every tetrapage target links privately.
add_library(tetrapage_warnings INTERFACE)
add_library(tetrapage::warnings ALIAS tetrapage_warnings)
target_compile_options(tetrapage_warnings INTERFACE -Wall -Wextra -Wpedantic
                       -Wnon-virtual-dtor -Wcast-align -Woverloaded-virtual)
# GCC's form; clang (the fuzz build) knows only -Wshadow, which also flags members.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  target_compile_options(tetrapage_warnings INTERFACE -Wshadow=local)
endif()
if(TETRAPAGE_WERROR)
  target_compile_options(tetrapage_warnings INTERFACE -Werror)
endif()

# Sanitizer build types: cmake -DCMAKE_BUILD_TYPE=asan|ubsan|tsan
set(_tp_san_common "-O1 -g -fno-omit-frame-pointer")
set(CMAKE_CXX_FLAGS_ASAN "${_tp_san_common} -fsanitize=address,undefined" CACHE STRING "" FORCE)
set(CMAKE_C_FLAGS_ASAN "${_tp_san_common} -fsanitize=address,undefined" CACHE STRING "" FORCE)
set(CMAKE_EXE_LINKER_FLAGS_ASAN "-fsanitize=address,undefined" CACHE STRING "" FORCE)
set(CMAKE_SHARED_LINKER_FLAGS_ASAN "-fsanitize=address,undefined" CACHE STRING "" FORCE)
set(CMAKE_CXX_FLAGS_UBSAN "${_tp_san_common} -fsanitize=undefined -fno-sanitize-recover=all" CACHE STRING "" FORCE)
set(CMAKE_C_FLAGS_UBSAN "${_tp_san_common} -fsanitize=undefined -fno-sanitize-recover=all" CACHE STRING "" FORCE)
set(CMAKE_EXE_LINKER_FLAGS_UBSAN "-fsanitize=undefined" CACHE STRING "" FORCE)
set(CMAKE_SHARED_LINKER_FLAGS_UBSAN "-fsanitize=undefined" CACHE STRING "" FORCE)
set(CMAKE_CXX_FLAGS_TSAN "${_tp_san_common} -fsanitize=thread" CACHE STRING "" FORCE)
set(CMAKE_C_FLAGS_TSAN "${_tp_san_common} -fsanitize=thread" CACHE STRING "" FORCE)
set(CMAKE_EXE_LINKER_FLAGS_TSAN "-fsanitize=thread" CACHE STRING "" FORCE)
set(CMAKE_SHARED_LINKER_FLAGS_TSAN "-fsanitize=thread" CACHE STRING "" FORCE)
