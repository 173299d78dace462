#include "handtrack/core/sequence.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace handtrack {
namespace fs = std::filesystem;
namespace {

[[noreturn]] void fail(const fs::path& file, const std::string& what) {
  throw std::runtime_error(file.string() + ": " + what);
}

double number_field(const nlohmann::json& j, const fs::path& file, const char* field, bool required,
                    double fallback) {
  if (!j.contains(field)) {
    if (required) fail(file, std::string("missing field '") + field + "'");
    return fallback;
  }
  if (!j[field].is_number()) fail(file, std::string("field '") + field + "' must be a number");
  return j[field].get<double>();
}

// Parses one CSV line into cells ("" for an empty cell).
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) cells.push_back(cell);
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  for (auto& c : cells) {
    c.erase(0, c.find_first_not_of(" \t\r"));
    c.erase(c.find_last_not_of(" \t\r") + 1);
  }
  return cells;
}

std::optional<double> parse_cell(const std::string& cell, const fs::path& file, size_t line) {
  if (cell.empty()) return std::nullopt;
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(cell, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != cell.size() || !std::isfinite(v)) {
    fail(file, "line " + std::to_string(line) + ": '" + cell + "' is not a number");
  }
  return v;
}

// Frame numbers are ints written as NNNNNN (SPEC.md); the largest a file name or CSV row may hold.
constexpr int kMaxFrameNumber = 999'999'999;

// Reads a CSV whose rows are: frame, then `values` numbers (possibly empty). Calls row(frame, cells).
template <typename RowFn>
void read_csv(const fs::path& file, size_t values, RowFn&& row) {
  std::ifstream in(file);
  if (!in) fail(file, "cannot open");
  std::string line;
  size_t n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line == "\r") continue;
    auto cells = split_csv(line);
    if (n == 1 && !cells.empty() && cells[0] == "frame") continue;  // header
    if (cells.size() != values + 1) {
      fail(file, "line " + std::to_string(n) + ": expected " + std::to_string(values + 1) + " cells, found " +
                     std::to_string(cells.size()));
    }
    const auto frame = parse_cell(cells[0], file, n);
    if (!frame || *frame < 0 || *frame > kMaxFrameNumber || *frame != std::floor(*frame)) {
      fail(file, "line " + std::to_string(n) + ": bad frame (a whole number in [0, " +
                     std::to_string(kMaxFrameNumber) + "])");
    }
    std::vector<std::optional<double>> parsed;
    for (size_t i = 1; i < cells.size(); ++i) parsed.push_back(parse_cell(cells[i], file, n));
    row(static_cast<int>(*frame), parsed);
  }
}

std::string header(bool joints) {
  std::string h = "frame";
  const int count = joints ? kNumJoints : kNumFingers;
  for (int i = 0; i < count; ++i) {
    const std::string stem(joints ? joint_name(i) : kFingerNames[static_cast<size_t>(i)]);
    for (const char* axis : {"_x", "_y", "_z"}) h += "," + stem + axis;
  }
  return h;
}

void write_vec(std::ostream& out, const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, ",%.3f,%.3f,%.3f", v.x(), v.y(), v.z());
  out << buf;
}

}  // namespace

fs::path frame_file(const fs::path& dir, int frame) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d.png", frame);
  return dir / name;
}

CameraIntrinsics read_camera_json(const fs::path& file) {
  std::ifstream in(file);
  if (!in) fail(file, "cannot open (every sequence directory needs a camera.json)");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    fail(file, std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) fail(file, "expected a JSON object");
  CameraIntrinsics c;
  const double w = number_field(j, file, "width", true, 0);
  const double h = number_field(j, file, "height", true, 0);
  if (w != std::floor(w) || h != std::floor(h) || w < 1 || h < 1 || w > 8192 || h > 8192) {
    fail(file, "fields 'width' and 'height' must be whole numbers in [8, 8192]");
  }
  c.width = static_cast<int>(w);
  c.height = static_cast<int>(h);
  c.fx = number_field(j, file, "fx", true, 0);
  c.fy = number_field(j, file, "fy", true, 0);
  c.cx = number_field(j, file, "cx", true, 0);
  c.cy = number_field(j, file, "cy", true, 0);
  c.depth_scale_mm = number_field(j, file, "depth_scale_mm", false, 1.0);
  c.fps = number_field(j, file, "fps", false, 30.0);
  if (auto why = c.problem(); !why.empty()) fail(file, why);
  return c;
}

void write_camera_json(const fs::path& file, const CameraIntrinsics& c) {
  nlohmann::json j = {{"width", c.width}, {"height", c.height}, {"fx", c.fx},
                      {"fy", c.fy},       {"cx", c.cx},         {"cy", c.cy},
                      {"depth_scale_mm", c.depth_scale_mm},     {"fps", c.fps}};
  std::ofstream out(file);
  if (!out) fail(file, "cannot write");
  out << j.dump(1) << "\n";
}

SequenceReader::SequenceReader(fs::path dir, Annotations annotations) : dir_(std::move(dir)) {
  if (!fs::is_directory(dir_)) fail(dir_, "not a directory");
  camera_ = read_camera_json(dir_ / "camera.json");
  const fs::path depth_dir = dir_ / "depth";
  if (!fs::is_directory(depth_dir)) fail(depth_dir, "missing (a sequence keeps its frames in depth/NNNNNN.png)");
  for (const auto& entry : fs::directory_iterator(depth_dir)) {
    const auto name = entry.path().filename().string();
    if (entry.path().extension() != ".png") continue;
    const auto stem = entry.path().stem().string();
    if (stem.empty() || !std::all_of(stem.begin(), stem.end(), [](char ch) { return ch >= '0' && ch <= '9'; })) {
      continue;
    }
    // A longer name is refused rather than wrapped.
    if (stem.size() > 9) {
      fail(entry.path(), "frame number " + stem + " is too large (at most " + std::to_string(kMaxFrameNumber) + ")");
    }
    frames_.push_back(std::stoi(stem));
  }
  std::sort(frames_.begin(), frames_.end());
  if (frames_.empty()) fail(depth_dir, "holds no NNNNNN.png frames");
  if (annotations == Annotations::kIgnore) return;

  if (const auto gt = dir_ / "groundtruth.csv"; fs::exists(gt)) {
    read_csv(gt, 3 * kNumFingers, [&](int frame, const std::vector<std::optional<double>>& v) {
      Fingertips tips;
      for (int f = 0; f < kNumFingers; ++f) {
        const auto i = static_cast<size_t>(3 * f);
        if (v[i] && v[i + 1] && v[i + 2]) tips[static_cast<size_t>(f)] = Eigen::Vector3d(*v[i], *v[i + 1], *v[i + 2]);
      }
      groundtruth_[frame] = tips;
    });
  }
  if (const auto jf = dir_ / "joints.csv"; fs::exists(jf)) {
    read_csv(jf, 3 * kNumJoints, [&](int frame, const std::vector<std::optional<double>>& v) {
      Joints joints;
      for (size_t k = 0; k < kNumJoints; ++k) {
        if (!v[3 * k] || !v[3 * k + 1] || !v[3 * k + 2]) fail(jf, "frame " + std::to_string(frame) + ": empty cell");
        joints[k] = Eigen::Vector3d(*v[3 * k], *v[3 * k + 1], *v[3 * k + 2]);
      }
      joints_[frame] = joints;
    });
  }
}

DepthImage SequenceReader::depth(size_t i) const {
  const auto file = frame_file(dir_ / "depth", frames_.at(i));
  const auto raw = read_png_gray16(file, PngSize{camera_.width, camera_.height});
  return DepthImage::from_raw(camera_, raw.pixels);
}

std::optional<Gray8Image> SequenceReader::labels(size_t i) const {
  const auto file = frame_file(dir_ / "labels", frames_.at(i));
  if (!fs::exists(file)) return std::nullopt;
  return read_png_gray8(file, PngSize{camera_.width, camera_.height});
}

Fingertips SequenceReader::fingertips(size_t i) const {
  const auto it = groundtruth_.find(frames_.at(i));
  return it == groundtruth_.end() ? Fingertips{} : it->second;
}

std::optional<Joints> SequenceReader::joints(size_t i) const {
  const auto it = joints_.find(frames_.at(i));
  if (it == joints_.end()) return std::nullopt;
  return it->second;
}

SequenceWriter::SequenceWriter(fs::path dir, const CameraIntrinsics& camera) : dir_(std::move(dir)), camera_(camera) {
  if (auto why = camera.problem(); !why.empty()) fail(dir_, "bad camera: " + why);
  fs::create_directories(dir_ / "depth");
  write_camera_json(dir_ / "camera.json", camera_);
}

SequenceWriter::~SequenceWriter() {
  try {
    flush();
  } catch (const std::exception&) {
    // Destructors must not throw; callers who care about CSV errors call flush() themselves.
  }
}

void SequenceWriter::write_depth(int frame, const DepthImage& depth) {
  write_depth_raw(frame, Gray16Image{depth.width(), depth.height(), 1, depth.to_raw()});
}

void SequenceWriter::write_depth_raw(int frame, const Gray16Image& raw) {
  write_png_gray16(frame_file(dir_ / "depth", frame), raw);
}

void SequenceWriter::write_labels(int frame, const Gray8Image& labels) {
  fs::create_directories(dir_ / "labels");
  write_png_gray8(frame_file(dir_ / "labels", frame), labels);
}

void SequenceWriter::write_fingertips(int frame, const Fingertips& tips) { groundtruth_[frame] = tips; }
void SequenceWriter::write_joints(int frame, const Joints& joints) { joints_[frame] = joints; }

void SequenceWriter::flush() {
  if (!groundtruth_.empty()) {
    std::ofstream out(dir_ / "groundtruth.csv");
    if (!out) fail(dir_ / "groundtruth.csv", "cannot write");
    out << header(false) << "\n";
    for (const auto& [frame, tips] : groundtruth_) {
      out << frame;
      for (const auto& tip : tips) {
        if (tip) write_vec(out, *tip);
        else out << ",,,";
      }
      out << "\n";
    }
  }
  if (!joints_.empty()) {
    std::ofstream out(dir_ / "joints.csv");
    if (!out) fail(dir_ / "joints.csv", "cannot write");
    out << header(true) << "\n";
    for (const auto& [frame, joints] : joints_) {
      out << frame;
      for (const auto& j : joints) write_vec(out, j);
      out << "\n";
    }
  }
}

}  // namespace handtrack
