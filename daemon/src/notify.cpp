#include "notify.hpp"

#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <cstdint>

namespace handtrack::daemon {

SystemdNotifier::SystemdNotifier() {
  uint64_t usec = 0;
  // > 0: enabled for this process (WATCHDOG_PID unset or ours).
  if (sd_watchdog_enabled(0, &usec) > 0) watchdog_ = std::chrono::microseconds(usec);
}

void SystemdNotifier::ready(const std::string& status) {
  sd_notifyf(0, "READY=1\nSTATUS=%s\nMAINPID=%lu", status.c_str(), static_cast<unsigned long>(getpid()));
}

void SystemdNotifier::watchdog() { sd_notify(0, "WATCHDOG=1"); }

void SystemdNotifier::status(const std::string& status) { sd_notifyf(0, "STATUS=%s", status.c_str()); }

void SystemdNotifier::stopping() { sd_notify(0, "STOPPING=1\nSTATUS=stopping"); }

}  // namespace handtrack::daemon
