# Ziegler-Nichols tuning and the paper report (issue 6).
add_executable(ziegler_nichols_test ${CMAKE_CURRENT_LIST_DIR}/ziegler_nichols_test.cc)
target_link_libraries(ziegler_nichols_test PRIVATE pidlab_tuner GTest::gtest_main)
gtest_discover_tests(ziegler_nichols_test DISCOVERY_TIMEOUT 60)

# The report library: re-evaluation against paper_tables.csv, contents, determinism.
add_executable(report_test ${CMAKE_CURRENT_LIST_DIR}/report_test.cc)
target_link_libraries(report_test PRIVATE pidlab_report GTest::gtest_main)
target_compile_definitions(report_test PRIVATE
  PIDLAB_PAPER_TABLES="${CMAKE_SOURCE_DIR}/../shared/reference/paper_tables.csv")
gtest_discover_tests(report_test DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 120)

# `pidlab report` end to end (full budgets and the LCM trio, in a private
# network namespace via pidlab launch --isolated): under 60 s, PNGs, exit 2.
add_test(NAME cli.report COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/cli/report_cli_test.sh
         $<TARGET_FILE:pidlab> ${CMAKE_SOURCE_DIR}/../shared/reference/paper_tables.csv)
set_tests_properties(cli.report PROPERTIES TIMEOUT 180 RUN_SERIAL TRUE)
