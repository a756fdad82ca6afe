// SPDX-License-Identifier: Apache-2.0
// Progress lines on stderr, "[  12.3s] what happened", timed from the start of a command; silent when
// quiet.
#pragma once

#include <chrono>
#include <cstdarg>
#include <cstdio>

namespace envpis::app {

class Progress {
 public:
  explicit Progress(bool quiet) : quiet_(quiet), t0_(std::chrono::steady_clock::now()) {}
  void line(const char* fmt, ...) __attribute__((format(printf, 2, 3))) {
    if (quiet_) return;
    std::fprintf(stderr, "[%6.1fs] ", elapsed());
    va_list ap;
    va_start(ap, fmt);
    std::vfprintf(stderr, fmt, ap);
    va_end(ap);
    std::fputc('\n', stderr);
  }
  double elapsed() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count(); }
  bool quiet() const { return quiet_; }

 private:
  bool quiet_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace envpis::app
