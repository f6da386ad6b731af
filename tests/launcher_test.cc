#include <gtest/gtest.h>
TEST(Launcher, Placeholder) {}
