// Bad-input checks shared by the parsers' tests: the reader must throw InputError with a
// one-line message that names the file and contains every given fragment.
#pragma once

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <string_view>

#include "limn/mesh/mesh.hpp"

namespace limn::test {

template <class Read, class... S>
void expect_bad_input(Read read, std::string_view data, std::string_view name, S... fragments) {
  try {
    read(data, name);
    FAIL() << "accepted bad input";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_THAT(msg, ::testing::HasSubstr(std::string(name) + ": "));
    for (const std::string_view f : {std::string_view(fragments)...})
      EXPECT_THAT(msg, ::testing::HasSubstr(std::string(f)));
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message must be one line: " << msg;
  }
}

}  // namespace limn::test
