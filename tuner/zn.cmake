# Ziegler-Nichols ultimate-gain tuning (issue 6), part of pidlab_tuner.
target_sources(pidlab_tuner PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src/ziegler_nichols.cc)
