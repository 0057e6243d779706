# Small helpers so that every library, test and benchmark is one line in its folder.

set(DREAMSENSE_WARNINGS -Wall -Wextra -Wpedantic -Wno-missing-field-initializers)

# ds_add_library(<name> SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates target dreamsense_<name> with alias dreamsense::<name>; headers under include/.
function(ds_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(dreamsense_${name} STATIC ${ARG_SOURCES})
  add_library(dreamsense::${name} ALIAS dreamsense_${name})
  target_include_directories(dreamsense_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(dreamsense_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  target_compile_options(dreamsense_${name} PRIVATE ${DREAMSENSE_WARNINGS})
endfunction()

# ds_add_test(<name> SOURCES ... DEPS ... [LABELS unit|analyzer|pipeline|dataset] [FIXTURES f]
#             [COST seconds] [RUN_SERIAL])
# One gtest executable per call; each TEST() becomes a ctest entry carrying the labels. COST (the
# seconds one of its tests takes, roughly) makes `ctest -j` start those tests first: a clean
# clone has no timings of an earlier run, and a long test started last leaves a core idle.
# RUN_SERIAL: its tests run with no other test beside them (real-time tests).
function(ds_add_test name)
  if(NOT DREAMSENSE_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "RUN_SERIAL" "COST" "SOURCES;DEPS;LABELS;FIXTURES" ${ARGN})
  if(NOT ARG_LABELS)
    set(ARG_LABELS unit)
  endif()
  add_executable(${name} ${ARG_SOURCES})
  # tools/sanitizers.sh builds only the tests that the sanitizer labels run (target
  # sanitizer_tests, defined at the end of the top-level CMakeLists.txt).
  if(ARG_LABELS MATCHES "unit|analyzer")
    set_property(GLOBAL APPEND PROPERTY DREAMSENSE_SANITIZER_TESTS ${name})
  endif()
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main GTest::gmock)
  target_compile_options(${name} PRIVATE ${DREAMSENSE_WARNINGS})
  # A test's own code is compiled for build time, not run time: the libraries it exercises keep
  # the preset's optimisation. apps/cli_test's unity file (2026-12-01): GCC 22 s at -O3, 15 s at
  # -O1; clang with ASan/UBSan (asan preset, Debug) 30 s at -O1, 12 s at -O0. Test files were
  # 40 % of a cold release build's CPU.
  target_compile_options(${name} PRIVATE $<$<CONFIG:Release>:-O1> $<$<CONFIG:Debug>:-O0>)
  target_compile_definitions(${name} PRIVATE
    DREAMSENSE_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    DREAMSENSE_BINARY_DIR="${PROJECT_BINARY_DIR}")
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  # gtest_discover_tests() passes PROPERTIES through a generated script that splits lists, so a
  # second label (or a fixture) would be lost: the labels and fixtures are set by a small script
  # of ours that ctest runs after the discovered tests are defined.
  gtest_discover_tests(${name}
    WORKING_DIRECTORY ${PROJECT_BINARY_DIR}
    TEST_LIST ${name}_TESTS
    DISCOVERY_TIMEOUT 60)
  set(props "LABELS \"${ARG_LABELS}\"")
  if(ARG_FIXTURES)
    string(APPEND props " FIXTURES_REQUIRED \"${ARG_FIXTURES}\"")
  endif()
  if(ARG_COST)
    string(APPEND props " COST ${ARG_COST}")
  endif()
  # Real-time tests (a live analysis keeps up with its devices or drops ticks): alone on the
  # machine, so that what they check does not depend on the test that runs beside them.
  if(ARG_RUN_SERIAL)
    string(APPEND props " RUN_SERIAL TRUE")
  endif()
  set(script ${CMAKE_CURRENT_BINARY_DIR}/${name}_properties.cmake)
  file(WRITE ${script}
       "foreach(t IN LISTS ${name}_TESTS)\n  set_tests_properties(\"\${t}\" PROPERTIES ${props})\nendforeach()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${script})
endfunction()

# ds_add_bench(<name> SOURCES ... DEPS ...)
function(ds_add_bench name)
  if(NOT DREAMSENSE_BUILD_BENCH)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} benchmark::benchmark)
  target_compile_options(${name} PRIVATE ${DREAMSENSE_WARNINGS})
endfunction()

# ds_add_analyzer(<name>): adds modalities/<name> and registers its analyser factories: the
# library dreamsense::<name> defines dreamsense::<name>::register_analyzers(AnalyzerRegistry&)
# (perception/analyzer_registry.hpp). The order of these lines is the registration order, which
# breaks ties when the runner orders analysers by their contracts.
function(ds_add_analyzer name)
  add_subdirectory(${name})
  set_property(GLOBAL APPEND PROPERTY DREAMSENSE_ANALYZERS ${name})
endfunction()

# ds_generate_analyzer_registry(): after the ds_add_analyzer() lines; writes the registry source
# and the library dreamsense::analyzers that links every registered analyser.
function(ds_generate_analyzer_registry)
  get_property(names GLOBAL PROPERTY DREAMSENSE_ANALYZERS)
  set(DS_ANALYZER_DECLARATIONS "")
  set(DS_ANALYZER_CALLS "")
  foreach(n ${names})
    string(APPEND DS_ANALYZER_DECLARATIONS
           "namespace dreamsense::${n} {\nvoid register_analyzers(AnalyzerRegistry& registry);\n}\n")
    string(APPEND DS_ANALYZER_CALLS "    ${n}::register_analyzers(r);\n")
  endforeach()
  set(out ${PROJECT_BINARY_DIR}/generated/analyzer_registry.cpp)
  configure_file(${PROJECT_SOURCE_DIR}/cmake/analyzer_registry.cpp.in ${out} @ONLY)
  add_library(dreamsense_analyzers STATIC ${out})
  add_library(dreamsense::analyzers ALIAS dreamsense_analyzers)
  target_link_libraries(dreamsense_analyzers PUBLIC dreamsense::perception)
  foreach(n ${names})
    target_link_libraries(dreamsense_analyzers PUBLIC dreamsense::${n})
  endforeach()
  target_compile_options(dreamsense_analyzers PRIVATE ${DREAMSENSE_WARNINGS})
endfunction()
