# Tests of logs, replay and plots (issue 5). Included by tests/CMakeLists.txt.
add_executable(log_reader_test ${CMAKE_CURRENT_LIST_DIR}/log_reader_test.cc)
target_link_libraries(log_reader_test PRIVATE pidlab_logreader GTest::gtest_main)
gtest_discover_tests(log_reader_test DISCOVERY_TIMEOUT 60)

add_executable(plot_test ${CMAKE_CURRENT_LIST_DIR}/plot_test.cc)
target_link_libraries(plot_test PRIVATE pidlab_plot GTest::gtest_main)
gtest_discover_tests(plot_test DISCOVERY_TIMEOUT 60)

# Integration: a real episode under `pidlab launch --isolated --log`, then
# replay, redrive, plot, and damaged copies of the log. The test creates its
# own network namespace (root needed) before anything touches LCM.
add_executable(replay_log_tamper ${CMAKE_CURRENT_LIST_DIR}/integration/replay_log_tamper.cc)
target_link_libraries(replay_log_tamper PRIVATE pidlab_lcmtypes)
add_test(NAME replay_integration
         COMMAND unshare -n bash ${CMAKE_CURRENT_LIST_DIR}/integration/replay_test.sh $<TARGET_FILE_DIR:pidlab>)
set_tests_properties(replay_integration PROPERTIES TIMEOUT 240 RUN_SERIAL TRUE FAIL_REGULAR_EXPRESSION "FAIL ")

# pidlab plot from an evaluation: PNG size and the data behind it against the trajectory.
add_test(NAME cli.plot COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/cli/plot_cli_test.sh $<TARGET_FILE:pidlab>)

# tools/lcm-spy: the types jar (skipped, not passed, without Java).
add_test(NAME cli.lcm_spy COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/cli/lcm_spy_test.sh ${CMAKE_SOURCE_DIR}/tools/lcm-spy)
set_tests_properties(cli.lcm_spy PROPERTIES SKIP_RETURN_CODE 77 FAIL_REGULAR_EXPRESSION "FAIL ")
