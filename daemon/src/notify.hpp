#pragma once
// The sd_notify(3) protocol through libsystemd: READY=1, WATCHDOG=1, STATUS=..., STOPPING=1.
// Without NOTIFY_SOCKET (not started by systemd) every call is a no-op.
#include <chrono>
#include <string>

namespace handtrack::daemon {

class SystemdNotifier {
 public:
  SystemdNotifier();
  // WatchdogSec= of the unit (WATCHDOG_USEC), zero when the watchdog is off.
  [[nodiscard]] std::chrono::microseconds watchdog_interval() const { return watchdog_; }
  void ready(const std::string& status);
  void watchdog();
  void status(const std::string& status);
  void stopping();

 private:
  std::chrono::microseconds watchdog_{0};
};

}  // namespace handtrack::daemon
