# Compiler settings and helpers shared by every Keel target.

find_program(KEEL_CCACHE ccache)
if(KEEL_CCACHE)
  set(CMAKE_CXX_COMPILER_LAUNCHER ${KEEL_CCACHE})
  set(CMAKE_C_COMPILER_LAUNCHER ${KEEL_CCACHE})
endif()

add_library(keel_warnings INTERFACE)
target_compile_options(keel_warnings INTERFACE -Wall -Wextra -Wpedantic -Wno-unused-parameter)

# libFuzzer (clang 14): everything instrumented for coverage, ASan and UBSan (any UB is a
# crash); the fuzz targets add -fsanitize=fuzzer at link time (tests/fuzz).
if(KEEL_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "KEEL_FUZZ needs clang: -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()

if(KEEL_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()

# keel_library(name SOURCES ... DEPS ...): a static library with warnings on.
function(keel_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE keel_warnings)
endfunction()

# keel_test(module/name SOURCES ... DEPS ...): a GoogleTest executable registered in CTest
# under the name module/name, run from the build directory. KEEL_SHARED_DIR points at the
# project's ../shared folder (tests skip, saying so, when it is absent).
function(keel_test test_name)
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES;DEPS" ${ARGN})
  string(REPLACE "/" "_" target "test_${test_name}")
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main keel_warnings)
  target_include_directories(${target} PRIVATE ${PROJECT_SOURCE_DIR})
  target_compile_definitions(${target} PRIVATE
    KEEL_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared"
    KEEL_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    KEEL_BINARY_DIR="${PROJECT_BINARY_DIR}")
  add_test(NAME ${test_name} COMMAND ${target})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 600)
  endif()
  set_tests_properties(${test_name} PROPERTIES TIMEOUT ${ARG_TIMEOUT})
endfunction()
