#include <gtest/gtest.h>
TEST(GlRenderer, Placeholder) {}
