#pragma once
// A private X server (Xvfb) for the tests that run the trainee window as a trainee would. It
// takes the first free display number from 140 up and goes away with the object.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

namespace hysim::testing {

class Xvfb {
 public:
  static constexpr const char* kBinary = "/usr/bin/Xvfb";
  static bool available() { return access(kBinary, X_OK) == 0; }

  // Starts Xvfb with one screen of width x height; false when it did not come up in 20 s.
  bool start(int width, int height) {
    for (int display = 140; display < 200; ++display) {
      if (std::filesystem::exists("/tmp/.X" + std::to_string(display) + "-lock")) continue;
      display_ = display;
      pid_ = launch(width, height);
      if (waitForSocket()) return true;
      stop();
    }
    return false;
  }
  ~Xvfb() { stop(); }
  std::string display() const { return ":" + std::to_string(display_); }

 private:
  pid_t launch(int width, int height) const {
    const std::string screen = std::to_string(width) + "x" + std::to_string(height) + "x24";
    const std::string name = display();
    const pid_t pid = fork();
    if (pid == 0) {
      const int null = open("/dev/null", O_WRONLY);
      dup2(null, 1);
      dup2(null, 2);
      execl(kBinary, kBinary, name.c_str(), "-screen", "0", screen.c_str(), "-nolisten", "tcp", nullptr);
      _exit(127);
    }
    return pid;
  }
  bool waitForSocket() const {
    const std::string socket = "/tmp/.X11-unix/X" + std::to_string(display_);
    for (int i = 0; i < 200; ++i) {
      if (std::filesystem::exists(socket)) return true;
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) return false;  // it exited (display taken?)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
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
