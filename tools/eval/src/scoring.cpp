#include "handtrack/eval/scoring.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

namespace handtrack::eval {

double fingertip_error_mm(const TrackerOutput& out, const Fingertips& truth) {
  double sum = 0.0;
  int n = 0;
  for (int f = 0; f < kNumFingers; ++f) {
    const auto& t = truth[static_cast<size_t>(f)];
    if (!t) continue;
    sum += (out.fingertips[static_cast<size_t>(f)] - *t).norm();
    ++n;
  }
  if (n == 0) return std::numeric_limits<double>::quiet_NaN();
  if (out.state == TrackingState::kNoHand) return std::numeric_limits<double>::infinity();
  return sum / n;
}

void SequenceScorer::add(const TrackerOutput& out, const Fingertips& truth) {
  ++score_.frames;
  if (!out.params.allFinite()) ++score_.nan_poses;
  if (out.detection_guided_won) ++score_.guided_wins;
  if (out.state != TrackingState::kNoHand) {
    ++score_.posed_frames;
    score_.left_frames += out.handedness == Handedness::kLeft ? 1 : 0;
    if (score_.expected_hand) {
      ++score_.hand_known_frames;
      score_.hand_correct += *score_.expected_hand == out.handedness ? 1 : 0;
    }
  }
  score_.per_frame_error_mm.push_back(fingertip_error_mm(out, truth));
}

namespace {
// Fills the statistics of `s` from its per-frame errors.
void summarise(SequenceScore& s) {
  double sum = 0.0;
  int annotated = 0;
  s.scored = s.without_pose = 0;
  s.max_error_mm = 0.0;
  std::array<int, kThresholdsMm.size()> below{};
  for (double e : s.per_frame_error_mm) {
    if (std::isnan(e)) continue;
    ++annotated;
    if (std::isinf(e)) {
      ++s.without_pose;
      continue;
    }
    ++s.scored;
    sum += e;
    s.max_error_mm = std::max(s.max_error_mm, e);
    for (size_t k = 0; k < kThresholdsMm.size(); ++k) below[k] += e < kThresholdsMm[k] ? 1 : 0;
  }
  s.mean_error_mm = s.scored > 0 ? sum / s.scored : std::numeric_limits<double>::quiet_NaN();
  for (size_t k = 0; k < kThresholdsMm.size(); ++k) {
    s.pct_below[k] = annotated > 0 ? 100.0 * below[k] / annotated : 0.0;
  }
}
}  // namespace

SequenceScore SequenceScorer::finish(double tracking_seconds) {
  summarise(score_);
  score_.fps = tracking_seconds > 0.0 ? score_.frames / tracking_seconds : 0.0;
  return score_;
}

SequenceScore overall(const std::vector<SequenceScore>& sequences) {
  SequenceScore all;
  all.name = "overall";
  double seconds = 0.0;
  for (const auto& s : sequences) {
    all.frames += s.frames;
    all.nan_poses += s.nan_poses;
    all.guided_wins += s.guided_wins;
    all.posed_frames += s.posed_frames;
    all.left_frames += s.left_frames;
    all.hand_known_frames += s.hand_known_frames;
    all.hand_correct += s.hand_correct;
    all.per_frame_error_mm.insert(all.per_frame_error_mm.end(), s.per_frame_error_mm.begin(),
                                  s.per_frame_error_mm.end());
    if (s.fps > 0.0) seconds += s.frames / s.fps;
  }
  summarise(all);
  all.fps = seconds > 0.0 ? all.frames / seconds : 0.0;
  return all;
}

std::vector<ScoreGroups> group_scores(const std::vector<SequenceScore>& sequences) {
  const std::array<std::pair<const char*, std::string (*)(const SequenceScore&)>, 3> properties = {{
      {"motion", [](const SequenceScore& s) { return s.motion; }},
      {"view", [](const SequenceScore& s) { return s.view; }},
      {"hand", [](const SequenceScore& s) { return s.expected_hand ? std::string(to_string(*s.expected_hand)) : ""; }},
  }};
  std::vector<ScoreGroups> out;
  for (const auto& [by, value_of] : properties) {
    std::map<std::string, std::vector<SequenceScore>> members;
    for (const auto& s : sequences) {
      if (const std::string v = value_of(s); !v.empty()) members[v].push_back(s);
    }
    if (members.empty()) continue;
    ScoreGroups g{by, {}};
    for (const auto& [value, list] : members) {
      g.groups.push_back(overall(list));
      g.groups.back().name = value;
    }
    out.push_back(std::move(g));
  }
  return out;
}

std::string format_table(const std::vector<SequenceScore>& sequences, const SequenceScore& total,
                         const std::vector<ScoreGroups>& groups) {
  std::string text;
  char line[160];
  std::snprintf(line, sizeof line, "%-14s %7s %9s %6s %6s %6s %6s %8s %7s\n", "sequence", "frames", "mean_mm", "<15",
                "<20", "<25", "<30", "fps", "guided");
  text += line;
  const auto row = [&](const SequenceScore& s) {
    std::snprintf(line, sizeof line, "%-14s %7d %9.2f %6.1f %6.1f %6.1f %6.1f %8.1f %7d\n", s.name.c_str(), s.frames,
                  s.mean_error_mm, s.pct_below[0], s.pct_below[1], s.pct_below[2], s.pct_below[3], s.fps,
                  s.guided_wins);
    text += line;
  };
  for (const auto& s : sequences) row(s);
  row(total);
  for (const auto& g : groups) {
    text += "\nby " + g.by + ":\n";
    for (const auto& s : g.groups) row(s);
  }
  return text;
}

nlohmann::json to_json(const std::vector<SequenceScore>& sequences, const SequenceScore& total,
                       const std::vector<ScoreGroups>& groups) {
  const auto pct = [](const SequenceScore& s) {
    nlohmann::json j = nlohmann::json::object();
    for (size_t k = 0; k < kThresholdsMm.size(); ++k) j[std::to_string(kThresholdsMm[k])] = s.pct_below[k];
    return j;
  };
  const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  // Of the frames with a pose: the share reported left, and where the truth is known, right.
  const auto hands = [&](const SequenceScore& s) {
    const auto share = [&](int n, int of) { return of > 0 ? number(100.0 * n / of) : nlohmann::json(nullptr); };
    nlohmann::json j = {{"pct_frames_left", share(s.left_frames, s.posed_frames)},
                        {"pct_frames_correct", share(s.hand_correct, s.hand_known_frames)}};
    if (s.expected_hand) j["expected"] = to_string(*s.expected_hand);
    return j;
  };
  // A frame that shows a hand but gets no pose is a miss (SPEC.md): its share of the annotated frames.
  const auto scores = [&](const SequenceScore& s) {
    const int annotated = s.scored + s.without_pose;
    return nlohmann::json{{"frames", s.frames},
                          {"frames_scored", s.scored},
                          {"frames_without_pose", s.without_pose},
                          {"pct_frames_without_pose", annotated > 0 ? number(100.0 * s.without_pose / annotated)
                                                                    : nlohmann::json(nullptr)},
                          {"nan_poses", s.nan_poses},
                          {"detection_guided_wins", s.guided_wins},
                          {"mean_fingertip_error_mm", number(s.mean_error_mm)},
                          {"max_fingertip_error_mm", number(s.max_error_mm)},
                          {"pct_frames_below_mm", pct(s)},
                          {"handedness", hands(s)},
                          {"fps", s.fps}};
  };
  nlohmann::json out;
  out["sequences"] = nlohmann::json::array();
  for (const auto& s : sequences) {
    nlohmann::json j = {{"name", s.name}};
    j.update(scores(s));
    if (!s.view.empty()) j["view"] = s.view;
    if (!s.motion.empty()) j["motion"] = s.motion;
    out["sequences"].push_back(std::move(j));
  }
  out["overall"] = scores(total);
  if (!groups.empty()) {
    out["groups"] = nlohmann::json::object();
    for (const auto& g : groups) {
      for (const auto& s : g.groups) out["groups"][g.by][s.name] = scores(s);
    }
  }
  return out;
}

}  // namespace handtrack::eval
