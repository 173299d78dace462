#pragma once
// handtrackd's configuration: a TOML file (default /etc/handtrack/handtrackd.toml) with every
// tracker parameter of the paper (defaults = the paper's values, from core's TrackerConfig) plus
// the service settings, then command-line overrides. docs/DAEMON.md lists every field.
//
// Error policy: loading and validation throw ConfigError, whose message is one line naming the
// file, the field and the allowed range ("FILE: tracker.particles = 0: allowed range 1..64").

#include "handtrack/core/tracker.hpp"
#include "handtrack/daemon/depth_source.hpp"

#include <array>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace handtrack::daemon {

inline constexpr const char* kDefaultConfigFile = "/etc/handtrack/handtrackd.toml";

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class LogLevel { kTrace, kDebug, kInfo, kWarn, kError, kOff };
const char* to_string(LogLevel level);
// "trace" | "debug" | "info" | "warn" | "error" | "off"; false when unknown.
bool parse_log_level(const std::string& text, LogLevel* level);

// Pipeline stages, in order; indexes the per-thread settings.
enum class Stage : int { kGrab = 0, kPreprocess = 1, kOptimize = 2, kPublish = 3 };
inline constexpr int kNumStages = 4;
const char* to_string(Stage stage);

struct PipelineConfig {
  int queue_capacity = 4;        // frames each queue between two stages can hold
  int pool_frames = 0;           // 0: enough for every queue and stage (computed)
  // -1: any CPU; otherwise the CPU a stage's thread is pinned to (grab, preprocess, optimize, publish).
  std::array<int, kNumStages> cpu{-1, -1, -1, -1};
  int realtime_priority = 0;     // SCHED_FIFO priority of the stage threads (preprocessing: one below), 0 = normal scheduling
  int stall_timeout_ms = 2000;   // a stage busy on one frame this long is stalled: watchdog pings stop
  int stats_interval_ms = 1000;  // statistics into the ring header, STATUS= and the debug summary
};

// The tracker's defaults, with late fusion (the shipped forest), and checks searched in the
// background: a service's frames never wait for a search (docs/TRACKER.md, "Checks in the
// background"), where handtrack-eval's runs must be the same every time.
inline TrackerConfig daemon_tracker_defaults() {
  TrackerConfig c;
  c.mode = EnergyMode::kLateFusion;
  c.background_checks = true;
  return c;
}

struct DaemonConfig {
  // [daemon]
  std::string source = "openni2";       // SPEC.md "Sources"
  std::string shm_name = "handtrack";
  int ring_capacity = 256;
  LogLevel log_level = LogLevel::kInfo;
  bool fast = false;                    // recordings/synthetic: no pacing
  bool loop = false;                    // recordings: play again at the end
  std::string record_dir;               // non-empty: write the raw depth there (SequenceWriter)
  bool single_thread = false;           // all stages on one thread (the baseline of the overlap)
  int64_t max_frames = 0;               // stop after this many frames (0 = never; tests)
  // [camera] (openni2 depth mode) and [synthetic]
  SourceOptions source_options;
  // [camera]: degrees the camera is turned about its optical axis (camera_roll.hpp): 0, 90, 180,
  // 270 (or -90, -180); each frame is tracked turned upright and its poses published turned back.
  int camera_roll_deg = 0;
  // [pipeline]
  PipelineConfig pipeline;
  // [tracker], [tracker.input], [tracker.energy], [tracker.optimizer], [tracker.scale]
  TrackerConfig tracker = daemon_tracker_defaults();
  // Part-classification forest (handtrack-train-forest) for late fusion (tracker.energy, Sec. 5);
  // empty: the shipped one (shipped_forest_path()).
  std::string forest_model;
  // Hand profile (handtrack-calibrate, Sec. 6): loaded with the configuration, its scales replace
  // tracker.scale; empty: tracker.scale as configured.
  std::string hand_profile;

  // Which file the values came from (empty: built-in defaults only).
  std::filesystem::path file;
};

// Reads `file` over the defaults. `explicit_file`: the user named it (a missing file is an error);
// otherwise a missing file leaves the defaults. Throws ConfigError.
DaemonConfig load_config(const std::filesystem::path& file, bool explicit_file);
// Same, from TOML text (for tests); `name` is used in messages.
DaemonConfig parse_config(const std::string& toml_text, const std::string& name);
// Checks every field's range; throws ConfigError naming `origin` (a file or "command line").
void validate(const DaemonConfig& config, const std::string& origin);

// The live-reloadable part (SIGHUP): tracker parameters and log level. Everything else needs a
// restart; `changed_but_not_live` lists such fields that differ between `a` and `b`.
std::vector<std::string> changed_but_not_live(const DaemonConfig& a, const DaemonConfig& b);

// Every field as "name = value" TOML text with the allowed range in a comment (--print-config).
std::string describe_config(const DaemonConfig& config);

}  // namespace handtrack::daemon
