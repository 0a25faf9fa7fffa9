#pragma once
// EXPECT_TRUE(contains(text, part)): on failure, says which part was missing from which text.
#include <gtest/gtest.h>

#include <string>

namespace epa::test {

inline ::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << part << "' not found in: " << text;
}

}  // namespace epa::test
