# Helpers every part uses to declare tests and benchmarks the same way.
include(GoogleTest)

# hapfluid_add_gtest(NAME SOURCES a.cpp b.cpp LIBS lib1 lib2 [LABELS label] [TIMEOUT s])
# A GoogleTest executable registered with ctest, one ctest entry per test case. Tests run from
# the source tree so they find config/ and ../shared/ by relative path. One label per executable
# (gtest_discover_tests would read a second as a property name); `slow` keeps it out of
# `make check`.
function(hapfluid_add_gtest name)
  cmake_parse_arguments(T "" "TIMEOUT;TEST_FILTER" "SOURCES;LIBS;LABELS" ${ARGN})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  add_executable(${name} ${T_SOURCES})
  target_link_libraries(${name} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main Threads::Threads)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  target_compile_definitions(${name} PRIVATE
    HAPFLUID_SOURCE_DIR="${HAPFLUID_SOURCE_DIR}" HAPFLUID_BINARY_DIR="${CMAKE_BINARY_DIR}")
  set(filter)
  if(T_TEST_FILTER)
    set(filter TEST_FILTER "${T_TEST_FILTER}")
  endif()
  gtest_discover_tests(${name}
    WORKING_DIRECTORY ${HAPFLUID_SOURCE_DIR}
    PROPERTIES TIMEOUT ${T_TIMEOUT} LABELS "${T_LABELS}"
    DISCOVERY_TIMEOUT 60
    ${filter})
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

# ThreadSanitizer variants, built beside the normal targets so that `make test` runs the race
# checks without a separate build folder (the normal targets get no TSan flag). GCC, the
# project's compiler: Debian 12's g++ brings libtsan2. Off when the whole build is already
# sanitized (-DHAPFLUID_SANITIZE=... or the fuzzing build), as TSan cannot be combined with ASan
# and would be redundant.
set(HAPFLUID_TSAN_FLAGS -fsanitize=thread -fno-omit-frame-pointer -g -O2)
if(NOT HAPFLUID_SANITIZE AND NOT HAPFLUID_FUZZ)
  include(CheckCXXSourceCompiles)
  set(CMAKE_REQUIRED_FLAGS -fsanitize=thread)
  set(CMAKE_REQUIRED_LINK_OPTIONS -fsanitize=thread)
  check_cxx_source_compiles("int main() { return 0; }" HAPFLUID_HAVE_TSAN)
  unset(CMAKE_REQUIRED_FLAGS)
  unset(CMAKE_REQUIRED_LINK_OPTIONS)
  if(NOT HAPFLUID_HAVE_TSAN)
    message(WARNING "no ThreadSanitizer runtime for ${CMAKE_CXX_COMPILER}: the *_tsan race tests are not built "
                    "(Debian: apt-get install libtsan2)")
  endif()
endif()

# hapfluid_add_tsan_library(NAME SOURCES a.cpp ... [INCLUDES dir] [LIBS lib ...] [OPTIONS flag ...])
# A static library compiled with ThreadSanitizer; whatever links it links the TSan runtime.
function(hapfluid_add_tsan_library name)
  cmake_parse_arguments(T "" "" "SOURCES;INCLUDES;LIBS;OPTIONS" ${ARGN})
  if(NOT HAPFLUID_HAVE_TSAN)
    return()
  endif()
  add_library(${name} STATIC ${T_SOURCES})
  target_include_directories(${name} PUBLIC ${T_INCLUDES})
  target_link_libraries(${name} PUBLIC ${T_LIBS})
  target_compile_options(${name} PRIVATE ${T_OPTIONS} ${HAPFLUID_TSAN_FLAGS})
  target_link_options(${name} INTERFACE -fsanitize=thread)
endfunction()

# hapfluid_add_tsan_gtest(NAME SOURCES a.cpp ... LIBS tsan_lib ... FILTER "Suite.*" [DEFINITIONS D=1 ...]
#                         [TIMEOUT s])
# A GoogleTest executable compiled with ThreadSanitizer, registered with ctest as one test that
# runs the FILTER cases. A reported race fails it (halt_on_error, exit code 66). It runs under
# run_without_aslr.sh: the TSan runtimes of GCC 12 and clang 14 abort ("unexpected memory
# mapping") on kernels that randomise mmap with more than 28 bits (vm.mmap_rnd_bits, 32 on some
# newer kernels); with ASLR off for the test process their fixed shadow layout always fits.
function(hapfluid_add_tsan_gtest name)
  cmake_parse_arguments(T "" "FILTER;TIMEOUT" "SOURCES;LIBS;DEFINITIONS" ${ARGN})
  if(NOT HAPFLUID_HAVE_TSAN)
    return()
  endif()
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  add_executable(${name} ${T_SOURCES})
  target_compile_options(${name} PRIVATE ${HAPFLUID_TSAN_FLAGS})
  target_compile_definitions(${name} PRIVATE ${T_DEFINITIONS})
  target_link_libraries(${name} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main Threads::Threads)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  add_test(NAME ${name}
           COMMAND sh ${HAPFLUID_SOURCE_DIR}/cmake/run_without_aslr.sh $<TARGET_FILE:${name}> --gtest_filter=${T_FILTER}
           WORKING_DIRECTORY ${HAPFLUID_SOURCE_DIR})
  set_tests_properties(${name} PROPERTIES
    TIMEOUT ${T_TIMEOUT} LABELS tsan
    ENVIRONMENT "TSAN_OPTIONS=halt_on_error=1:exitcode=66:second_deadlock_stack=1")
endfunction()
