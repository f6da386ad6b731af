# Plots (gnuplot-driven PNG figures) and log replay: owned by the logs/replay work.
# Included by tools/CMakeLists.txt after add_executable(pidlab).

# PNG figures through gnuplot: a small library the report reuses.
add_library(pidlab_plot STATIC ${CMAKE_CURRENT_SOURCE_DIR}/plot.cc ${CMAKE_CURRENT_SOURCE_DIR}/loop_figure.cc)
target_include_directories(pidlab_plot PUBLIC ${CMAKE_CURRENT_SOURCE_DIR})

target_link_libraries(pidlab PRIVATE pidlab_plot)
target_sources(pidlab PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/plot_sources.cc)
