#pragma once
// A private X server (Xvfb) for the tests that run the trainee window as a trainee would. Xvfb
// picks a free display number itself (-displayfd), so tests running side by side do not meet;
// the server goes away with the object.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

namespace hysim::testing {

class Xvfb {
 public:
  static constexpr const char* kBinary = "/usr/bin/Xvfb";
  static bool available() { return access(kBinary, X_OK) == 0; }

  // Starts Xvfb with one screen of width x height; false when it did not come up in 20 s.
  bool start(int width, int height) {
    int fds[2];
    if (pipe(fds) != 0) return false;
    pid_ = launch(width, height, fds[1]);
    close(fds[1]);
    display_ = readDisplay(fds[0]);
    close(fds[0]);
    if (display_ < 0) stop();
    return display_ >= 0;
  }
  ~Xvfb() { stop(); }
  std::string display() const { return ":" + std::to_string(display_); }

 private:
  static pid_t launch(int width, int height, int display_fd) {
    const std::string screen = std::to_string(width) + "x" + std::to_string(height) + "x24";
    const std::string fd = std::to_string(display_fd);
    const pid_t pid = fork();
    if (pid == 0) {
      const int null = open("/dev/null", O_WRONLY);
      dup2(null, 1);
      dup2(null, 2);
      execl(kBinary, kBinary, "-displayfd", fd.c_str(), "-screen", "0", screen.c_str(), "-nolisten", "tcp", nullptr);
      _exit(127);
    }
    return pid;
  }
  // The display number Xvfb writes once it listens; -1 when it does not within 20 s.
  static int readDisplay(int fd) {
    std::string text;
    pollfd p{fd, POLLIN, 0};
    while (text.find('\n') == std::string::npos && poll(&p, 1, 20000) > 0) {
      char buf[32];
      const ssize_t n = read(fd, buf, sizeof buf);
      if (n <= 0) break;
      text.append(buf, static_cast<std::size_t>(n));
    }
    if (text.find('\n') == std::string::npos) return -1;
    return std::atoi(text.c_str());
  }
  void stop() {
    if (pid_ <= 0) return;
    kill(pid_, SIGTERM);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
  }
  int display_ = -1;
  pid_t pid_ = -1;
};

}  // namespace hysim::testing
