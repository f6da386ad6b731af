# Lockstep steps/s of the LCM trio next to a raw LCM round trip (issue 3).
# Run: pidlab launch --isolated -- trio_bench [ROUND_TRIPS] [HORIZON_S]
add_executable(trio_bench ${CMAKE_CURRENT_LIST_DIR}/trio_bench.cc)
target_link_libraries(trio_bench PRIVATE pidlab_lcm)
