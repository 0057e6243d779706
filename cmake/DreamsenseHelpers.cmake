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

# ds_add_test(<name> SOURCES ... DEPS ... [LABELS unit|analyzer|pipeline|dataset] [FIXTURES f])
# One gtest executable per call; each TEST() becomes a ctest entry carrying the labels.
function(ds_add_test name)
  if(NOT DREAMSENSE_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS;FIXTURES" ${ARGN})
  if(NOT ARG_LABELS)
    set(ARG_LABELS unit)
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main GTest::gmock)
  target_compile_options(${name} PRIVATE ${DREAMSENSE_WARNINGS})
  target_compile_definitions(${name} PRIVATE
    DREAMSENSE_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    DREAMSENSE_BINARY_DIR="${PROJECT_BINARY_DIR}")
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  # A list property must reach set_tests_properties as one argument: escape its semicolons.
  string(REPLACE ";" "\\;" labels "${ARG_LABELS}")
  string(REPLACE ";" "\\;" fixtures "${ARG_FIXTURES}")
  gtest_discover_tests(${name}
    WORKING_DIRECTORY ${PROJECT_BINARY_DIR}
    PROPERTIES LABELS "${labels}" FIXTURES_REQUIRED "${fixtures}"
    DISCOVERY_TIMEOUT 60)
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
