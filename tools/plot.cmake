# Plots (gnuplot-driven PNG figures) and log replay: owned by the logs/replay work.
# Included by tools/CMakeLists.txt after add_executable(pidlab).

# PNG figures through gnuplot (plot.h) and the standard y/e/u/n loop figure
# (loop_figure.h): a small library the report reuses.
add_library(pidlab_plot STATIC ${CMAKE_CURRENT_SOURCE_DIR}/plot.cc ${CMAKE_CURRENT_SOURCE_DIR}/loop_figure.cc)
target_include_directories(pidlab_plot PUBLIC ${CMAKE_CURRENT_SOURCE_DIR})

# Reading pidlab episodes back from LCM logs (log_reader.h): pure, no printing.
add_library(pidlab_logreader STATIC ${CMAKE_CURRENT_SOURCE_DIR}/log_reader.cc)
target_include_directories(pidlab_logreader PUBLIC ${CMAKE_CURRENT_SOURCE_DIR})
target_link_libraries(pidlab_logreader PUBLIC pidlab_lcm pidlab_lcmtypes pidlab_tuner PkgConfig::LCM)

target_sources(pidlab PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/plot_sources.cc)
target_link_libraries(pidlab PRIVATE pidlab_plot pidlab_logreader)
