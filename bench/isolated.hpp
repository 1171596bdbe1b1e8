// Runs a benchmark case in a child process, so its peak resident set (wait4's ru_maxrss) is its
// own, under an address-space cap so a case that does not fit fails with bad_alloc instead of
// waking the kernel's OOM killer.
#pragma once

#include <fmt/format.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <new>
#include <string>

namespace limn::bench {

struct Outcome {
  bool ok = false;
  double ms = 0, peak_mb = 0;
  size_t points = 0;
  std::string why;
};

inline Outcome run_isolated(const std::function<size_t()>& fn, double cap_gb) {
  int fd[2];
  if (pipe(fd) != 0) return {false, 0, 0, 0, "pipe failed"};
  const pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    rlimit lim{};
    lim.rlim_cur = lim.rlim_max = rlim_t(cap_gb * double(1ull << 30));
    setrlimit(RLIMIT_AS, &lim);
    double msg[2] = {0, 0};
    int code = 0;
    try {
      const auto t0 = std::chrono::steady_clock::now();
      const size_t n = fn();
      msg[0] =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      msg[1] = double(n);
    } catch (const std::bad_alloc&) {
      code = 3;
    } catch (const std::exception&) {
      code = 4;
    }
    if (write(fd[1], msg, sizeof msg) != ssize_t(sizeof msg)) code = 5;
    _exit(code);
  }
  close(fd[1]);
  double msg[2] = {0, 0};
  const ssize_t got = read(fd[0], msg, sizeof msg);
  close(fd[0]);
  int status = 0;
  rusage ru{};
  wait4(pid, &status, 0, &ru);
  Outcome o;
  o.peak_mb = double(ru.ru_maxrss) / 1024.0;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0 && got == ssize_t(sizeof msg)) {
    o.ok = true;
    o.ms = msg[0];
    o.points = size_t(msg[1]);
  } else if (WIFEXITED(status) && WEXITSTATUS(status) == 3) {
    o.why = fmt::format("out of memory under the {:.0f} GiB cap", cap_gb);
  } else {
    o.why = WIFSIGNALED(status) ? fmt::format("killed by signal {}", WTERMSIG(status))
                                : fmt::format("failed (exit {})", WEXITSTATUS(status));
  }
  return o;
}

}  // namespace limn::bench
