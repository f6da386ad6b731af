# Tests of the LCM trio (issue 3). Included by tests/CMakeLists.txt.
add_executable(trio_protocol_test ${CMAKE_CURRENT_LIST_DIR}/trio_protocol_test.cc)
target_link_libraries(trio_protocol_test PRIVATE pidlab_lcm GTest::gtest_main)
gtest_discover_tests(trio_protocol_test)

# Helpers of the integration tests, built next to the pidlab binaries.
add_executable(trio_log_check ${CMAKE_CURRENT_LIST_DIR}/integration/trio_log_check.cc)
target_link_libraries(trio_log_check PRIVATE pidlab_logreader)
add_executable(trio_stranger ${CMAKE_CURRENT_LIST_DIR}/integration/trio_stranger.cc)
target_link_libraries(trio_stranger PRIVATE pidlab_lcmtypes)

# Each integration test creates its own network namespace (root needed).
foreach(case identity faults stranger kill log log_repair)
  add_test(NAME trio_integration_${case}
           COMMAND unshare -n bash ${CMAKE_CURRENT_LIST_DIR}/integration/trio_test.sh
                   $<TARGET_FILE_DIR:pidlab> ${case})
  set_tests_properties(trio_integration_${case} PROPERTIES TIMEOUT 120 RUN_SERIAL TRUE
                       FAIL_REGULAR_EXPRESSION "FAIL ")
endforeach()
