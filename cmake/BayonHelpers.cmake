# SPDX-License-Identifier: BSD-3-Clause
# One library per ext/ folder (bayon_<name>), tests registered beside their sources.

set(BAYON_WARNINGS -Wall -Wextra)
if(BAYON_WERROR)
  list(APPEND BAYON_WARNINGS -Werror)
endif()

if(BAYON_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer
                      -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
  # With clang, the libFuzzer harnesses of tests/fuzz are built too; they
  # instrument the readers they drive for coverage (tests/fuzz/CMakeLists.txt).
  if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    set(BAYON_FUZZ ON)
  endif()
endif()

# bayon_add_library(NAME core SRCS a.cc b.cc PUBLIC_LINK ... PRIVATE_LINK ...)
function(bayon_add_library)
  cmake_parse_arguments(ARG "" "NAME" "SRCS;PUBLIC_LINK;PRIVATE_LINK" ${ARGN})
  set(target bayon_${ARG_NAME})
  add_library(${target} STATIC ${ARG_SRCS})
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
  target_compile_options(${target} PRIVATE ${BAYON_WARNINGS})
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_LINK} PRIVATE ${ARG_PRIVATE_LINK})
endfunction()

# bayon_add_test(NAME x_test SRCS x_test.cc LINK_LIBS bayon_x [LABELS e2e]
#                [SANITIZE] [TIMEOUT 300])
# A sanitizer build makes the unit tests and only those end-to-end tests
# marked SANITIZE: the others would take most of its build time and are not
# run there.
function(bayon_add_test)
  cmake_parse_arguments(ARG "SANITIZE" "NAME;TIMEOUT" "SRCS;LINK_LIBS;LABELS" ${ARGN})
  set(labels unit)
  if(ARG_LABELS)
    set(labels ${ARG_LABELS})
  endif()
  if(BAYON_SANITIZE AND "e2e" IN_LIST labels AND NOT ARG_SANITIZE)
    return()
  endif()
  add_executable(${ARG_NAME} ${ARG_SRCS})
  target_compile_options(${ARG_NAME} PRIVATE ${BAYON_WARNINGS})
  target_link_libraries(${ARG_NAME} PRIVATE ${ARG_LINK_LIBS} bayon_testing
                        GTest::gtest GTest::gtest_main GTest::gmock)
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 600)
  endif()
  if(BAYON_SANITIZE)
    # Instrumented pixel loops run 10 to 20 times slower (the temple pipeline
    # takes about 7 minutes instead of 50 s).
    math(EXPR ARG_TIMEOUT "${ARG_TIMEOUT} * 4")
  endif()
  # No COST: ctest -j orders the tests by their measured times only where
  # the project sets none; scripts/test.sh seeds those times in a fresh
  # build folder (tests/ctest_costs*.txt).
  gtest_discover_tests(${ARG_NAME}
    DISCOVERY_MODE PRE_TEST
    WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}
    PROPERTIES LABELS "${labels}" TIMEOUT ${ARG_TIMEOUT})
endfunction()

include(GoogleTest)
