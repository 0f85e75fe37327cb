include(GoogleTest)

# ivoa_add_gtest(name SOURCES ... DEPS ... [LABELS ...]): a GoogleTest
# executable whose cases are registered with CTest one by one.
function(ivoa_add_gtest name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ivoa_warnings GTest::gtest GTest::gtest_main ${ARG_DEPS})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 120 TEST_LIST ${name}_TESTS)
  # The labels go on in a file CTest reads after the discovered tests: given
  # as gtest_discover_tests PROPERTIES, a list of labels is split into more
  # properties on the way, and only the first label stuck.
  set(labels_file ${CMAKE_CURRENT_BINARY_DIR}/${name}_labels.cmake)
  file(WRITE ${labels_file}
    "foreach(test IN LISTS ${name}_TESTS)\n"
    "  set_tests_properties(\"\${test}\" PROPERTIES LABELS \"${ARG_LABELS};unit\")\n"
    "endforeach()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${labels_file})
endfunction()

# ivoa_add_netns_test(name COMMAND ... [TIMEOUT s] [LABELS ...] [ALONE]): runs
# COMMAND inside a private network namespace with only a multicast-capable
# loopback (tests/harness/in_netns.sh), so real udpm LCM traffic never leaves
# the test. Reported as skipped, with the reason, where namespaces are
# forbidden. ALONE runs it with no other test beside it: a zero-loss check of
# 3.5 MB stereo pairs at 30 Hz holds only while the receiver gets a core, and
# the kernel's 8 MB socket buffer covers about two pairs (66 ms) of starving.
function(ivoa_add_netns_test name)
  cmake_parse_arguments(ARG "ALONE" "TIMEOUT" "COMMAND;LABELS" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  add_test(NAME ${name}
    COMMAND ${CMAKE_SOURCE_DIR}/tests/harness/in_netns.sh ${ARG_COMMAND}
    WORKING_DIRECTORY ${CMAKE_BINARY_DIR})
  set_tests_properties(${name} PROPERTIES
    SKIP_RETURN_CODE 77
    TIMEOUT ${ARG_TIMEOUT}
    LABELS "${ARG_LABELS};integration"
    ENVIRONMENT "IVOA_BUILD_DIR=${CMAKE_BINARY_DIR};IVOA_SOURCE_DIR=${CMAKE_SOURCE_DIR}")
  if(ARG_ALONE)
    set_tests_properties(${name} PROPERTIES RUN_SERIAL TRUE)
  endif()
endfunction()
