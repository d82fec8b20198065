# Helpers every part uses to declare tests and benchmarks the same way.
include(GoogleTest)

# hapfluid_add_gtest(NAME SOURCES a.cpp b.cpp LIBS lib1 lib2 [LABELS l1] [TIMEOUT s])
# A GoogleTest executable registered with ctest, one ctest entry per test case. Tests run from
# the source tree so they find config/ and ../shared/ by relative path.
function(hapfluid_add_gtest name)
  cmake_parse_arguments(T "" "TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  add_executable(${name} ${T_SOURCES})
  target_link_libraries(${name} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main Threads::Threads)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  target_compile_definitions(${name} PRIVATE
    HAPFLUID_SOURCE_DIR="${HAPFLUID_SOURCE_DIR}" HAPFLUID_BINARY_DIR="${CMAKE_BINARY_DIR}")
  gtest_discover_tests(${name}
    WORKING_DIRECTORY ${HAPFLUID_SOURCE_DIR}
    PROPERTIES TIMEOUT ${T_TIMEOUT} LABELS "${T_LABELS}"
    DISCOVERY_TIMEOUT 60)
endfunction()

# hapfluid_add_bench(NAME SOURCES ... LIBS ...)
# A benchmark executable in build/bench/. `make bench` runs every executable there as
#   build/bench/NAME --out out/bench/NAME.json
# and each writes a JSON list of {"bench", "params", "metrics"} records.
function(hapfluid_add_bench name)
  cmake_parse_arguments(B "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${B_SOURCES})
  target_link_libraries(${name} PRIVATE ${B_LIBS} Threads::Threads)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${HAPFLUID_BENCH_DIR})
  target_compile_definitions(${name} PRIVATE HAPFLUID_SOURCE_DIR="${HAPFLUID_SOURCE_DIR}")
endfunction()
