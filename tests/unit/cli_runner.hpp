// Running the limn executable from tests as scripts do: a scratch folder per test, exit code,
// stdout and stderr captured, and the folder's files listed (to catch leftovers of failed
// writes).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace limn::test {

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct CliResult {
  int code = -1;
  std::string out, err;
};

/// A fixture with a fresh scratch folder (dir()) and limn(args) running the CLI.
class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("limn-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->test_suite_name() + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  const std::filesystem::path& dir() const { return dir_; }

  /// Runs `limn args` (args are passed to the shell as they are).
  CliResult limn(const std::string& args) const {
    const std::filesystem::path out = dir_.string() + ".out", err = dir_.string() + ".err";
    const std::string cmd = std::string("'") + LIMN_CLI + "' " + args + " >'" + out.string() +
                            "' 2>'" + err.string() + "' </dev/null";
    const int status = std::system(cmd.c_str());
    CliResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.out = slurp(out), r.err = slurp(err);
    std::filesystem::remove(out), std::filesystem::remove(err);
    return r;
  }

  /// The names of the files in the scratch folder, sorted (to catch leftovers of failed writes).
  std::vector<std::string> files() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir_))
      names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

  /// Writes `text` to a file of the scratch folder; returns its path.
  std::filesystem::path write(const std::string& name, const std::string& text) const {
    const std::filesystem::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

  /// The path in single quotes, for a command line.
  // (Appends rather than operator+: GCC 12's -Wrestrict misfires on the latter at -O3.)
  static std::string q(const std::filesystem::path& p) {
    std::string s(1, '\'');
    s.append(p.string());
    s.push_back('\'');
    return s;
  }

  using Result = CliResult;
  std::filesystem::path dir_;
};

}  // namespace limn::test
