#include "handtrack/eval/scoring.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <stdexcept>

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

void JointErrors::add(const Joints& tracked, const Joints& truth) {
  const auto error = [&](int joint) {
    return (tracked[static_cast<size_t>(joint)] - truth[static_cast<size_t>(joint)]).norm();
  };
  const double wrist = error(kWristJoint);
  double all = wrist;
  kind_sum_mm[0] += wrist;
  for (int k = 0; k + 1 < static_cast<int>(kJointKinds.size()); ++k) {  // each finger's k-th joint from its base
    double kind = 0.0;
    for (int f = 0; f < kNumFingers; ++f) kind += error(joint_index(f, k));
    kind_sum_mm[static_cast<size_t>(k) + 1] += kind / kNumFingers;
    all += kind;
  }
  sum_mm += all / kNumJoints;
  ++frames;
}

void JointErrors::add(const JointErrors& other) {
  frames += other.frames;
  sum_mm += other.sum_mm;
  for (size_t k = 0; k < kind_sum_mm.size(); ++k) kind_sum_mm[k] += other.kind_sum_mm[k];
}

double JointErrors::mean_mm() const {
  return frames > 0 ? sum_mm / frames : std::numeric_limits<double>::quiet_NaN();
}

double JointErrors::kind_mean_mm(size_t kind) const {
  return frames > 0 ? kind_sum_mm.at(kind) / frames : std::numeric_limits<double>::quiet_NaN();
}

namespace {
// A pose to score joints on: reported, and finite (a NaN pose is counted as such, not scored).
bool scorable(const TrackerOutput& out) { return out.state != TrackingState::kNoHand && out.params.allFinite(); }
}  // namespace

void SequenceScorer::add(const TrackerOutput& out, const Fingertips& truth, const std::optional<Joints>& joints) {
  ++score_.frames;
  if (joints && scorable(out)) score_.joints.add(out.joints, *joints);
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
    s.pct_below[k] = annotated > 0 ? 100.0 * below[k] / annotated : std::numeric_limits<double>::quiet_NaN();
  }
}
}  // namespace

SequenceScore SequenceScorer::finish(double tracking_seconds) {
  summarise(score_);
  score_.fps = tracking_seconds > 0.0 ? score_.frames / tracking_seconds : 0.0;
  return score_;
}

namespace {
// The scores of hand `index` of the sequences that have one, pooled; its side where they agree.
SequenceScore pool_hand(const std::vector<SequenceScore>& sequences, size_t index) {
  std::vector<SequenceScore> members;
  for (const auto& s : sequences) {
    if (index < s.hands.size()) members.push_back(s.hands[index]);
  }
  SequenceScore pooled = overall(members);
  pooled.name = members.front().name;
  pooled.expected_hand = members.front().expected_hand;
  for (const auto& m : members) {
    if (m.expected_hand != pooled.expected_hand) pooled.expected_hand.reset();
  }
  return pooled;
}
}  // namespace

SequenceScore overall(const std::vector<SequenceScore>& sequences) {
  SequenceScore all;
  all.name = "overall";
  double seconds = 0.0;
  size_t most_hands = 0;
  for (const auto& s : sequences) {
    most_hands = std::max(most_hands, s.hands.size());
    all.identity_swaps += s.identity_swaps;
    all.phantom_frames += s.phantom_frames;
    all.phantom_hands += s.phantom_hands;
    all.frames += s.frames;
    all.nan_poses += s.nan_poses;
    all.guided_wins += s.guided_wins;
    all.posed_frames += s.posed_frames;
    all.left_frames += s.left_frames;
    all.hand_known_frames += s.hand_known_frames;
    all.hand_correct += s.hand_correct;
    all.joints.add(s.joints);
    all.per_frame_error_mm.insert(all.per_frame_error_mm.end(), s.per_frame_error_mm.begin(),
                                  s.per_frame_error_mm.end());
    if (s.fps > 0.0) seconds += s.frames / s.fps;
  }
  summarise(all);
  all.fps = seconds > 0.0 ? all.frames / seconds : 0.0;
  for (size_t k = 0; k < most_hands; ++k) all.hands.push_back(pool_hand(sequences, k));
  return all;
}

std::optional<double> hand_distance_mm(const TrackerOutput& tracked, const Fingertips& truth) {
  if (tracked.state == TrackingState::kNoHand) return std::nullopt;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (size_t f = 0; f < kNumFingers; ++f) {
    if (!truth[f]) continue;
    sum += tracked.fingertips[f] - *truth[f];
    ++n;
  }
  if (n == 0) return std::nullopt;
  const double d = sum.norm() / n;
  return std::isfinite(d) ? std::optional<double>(d) : std::nullopt;
}

HandMatch match_hands(std::span<const TrackerOutput> tracked, std::span<const Fingertips> truth, double radius_mm) {
  const size_t nt = tracked.size(), ng = truth.size();
  // Admissible pairs: distance[t][g], or nullopt beyond the radius.
  std::vector<std::vector<std::optional<double>>> distance(nt, std::vector<std::optional<double>>(ng));
  for (size_t t = 0; t < nt; ++t) {
    for (size_t g = 0; g < ng; ++g) {
      const auto d = hand_distance_mm(tracked[t], truth[g]);
      if (d && *d <= radius_mm) distance[t][g] = d;
    }
  }
  // Depth-first over the tracked hands: each takes a free ground-truth hand within reach, or none.
  // Best = the most pairs, then the smallest total distance (ties: the first found, so the result
  // does not depend on floating-point noise in a symmetric case's order).
  HandMatch best{std::vector<int>(nt, -1), std::vector<int>(ng, -1)};
  int best_pairs = 0;
  double best_total = 0.0;
  HandMatch current = best;
  const auto search = [&](const auto& self, size_t t, int pairs, double total) -> void {
    if (t == nt) {
      if (pairs > best_pairs || (pairs == best_pairs && total < best_total)) {
        best = current;
        best_pairs = pairs;
        best_total = total;
      }
      return;
    }
    for (size_t g = 0; g < ng; ++g) {
      if (!distance[t][g] || current.tracked_of_truth[g] >= 0) continue;
      current.truth_of_tracked[t] = static_cast<int>(g);
      current.tracked_of_truth[g] = static_cast<int>(t);
      self(self, t + 1, pairs + 1, total + *distance[t][g]);
      current.truth_of_tracked[t] = -1;
      current.tracked_of_truth[g] = -1;
    }
    self(self, t + 1, pairs, total);
  };
  search(search, 0, 0, 0.0);
  return best;
}

HandsScorer::HandsScorer(std::string name, const std::vector<std::optional<Handedness>>& truth_hands)
    : last_id_(truth_hands.size(), 0) {
  score_.name = std::move(name);
  for (size_t k = 0; k < truth_hands.size(); ++k) {
    SequenceScore hand;
    hand.name = "hand " + std::to_string(k);
    hand.expected_hand = truth_hands[k];
    score_.hands.push_back(std::move(hand));
  }
}

HandMatch HandsScorer::add(std::span<const TrackerOutput> tracked, std::span<const Fingertips> truth,
                           std::span<const std::optional<Joints>> joints) {
  if (truth.size() != score_.hands.size() || (!joints.empty() && joints.size() != truth.size())) {
    throw std::invalid_argument("HandsScorer::add: " + std::to_string(truth.size()) + " ground-truth hands (" +
                                std::to_string(joints.size()) + " with joints), expected " +
                                std::to_string(score_.hands.size()));
  }
  ++score_.frames;
  for (const auto& out : tracked) {
    if (out.state == TrackingState::kNoHand) continue;
    if (!out.params.allFinite()) ++score_.nan_poses;
    if (out.detection_guided_won) ++score_.guided_wins;
  }
  const HandMatch match = match_hands(tracked, truth);
  int phantoms = 0;
  for (size_t t = 0; t < tracked.size(); ++t) {
    phantoms += tracked[t].state != TrackingState::kNoHand && match.truth_of_tracked[t] < 0 ? 1 : 0;
  }
  score_.phantom_frames += phantoms > 0 ? 1 : 0;
  score_.phantom_hands += phantoms;
  // The frame's error over all hands' annotated fingertips (SPEC.md: the mean over a frame's
  // annotated fingertips): sum_h n_h e_h / sum_h n_h, +inf if an annotated hand was missed.
  double tip_error_sum = 0.0;
  int tips = 0;
  bool missed = false;
  for (size_t g = 0; g < truth.size(); ++g) {
    SequenceScore& hand = score_.hands[g];
    ++hand.frames;
    const int t = match.tracked_of_truth[g];
    const int annotated = static_cast<int>(std::count_if(truth[g].begin(), truth[g].end(),
                                                         [](const auto& tip) { return tip.has_value(); }));
    double error = std::numeric_limits<double>::quiet_NaN();
    if (annotated > 0) error = t < 0 ? std::numeric_limits<double>::infinity() : fingertip_error_mm(tracked[static_cast<size_t>(t)], truth[g]);
    hand.per_frame_error_mm.push_back(error);
    if (annotated > 0 && t < 0) missed = true;
    if (annotated > 0 && t >= 0) {
      tip_error_sum += error * annotated;
      tips += annotated;
    }
    uint32_t id = 0;
    if (t >= 0) {
      const TrackerOutput& out = tracked[static_cast<size_t>(t)];
      id = out.hand_id;
      if (!joints.empty() && joints[g] && scorable(out)) hand.joints.add(out.joints, *joints[g]);
      ++hand.posed_frames;
      hand.left_frames += out.handedness == Handedness::kLeft ? 1 : 0;
      if (hand.expected_hand) {
        ++hand.hand_known_frames;
        hand.hand_correct += out.handedness == *hand.expected_hand ? 1 : 0;
      }
    }
    // A swap: matched in this frame and the last, to hands of different ids.
    if (id != 0 && last_id_[g] != 0 && id != last_id_[g]) ++hand.identity_swaps;
    last_id_[g] = id;
  }
  double frame_error = std::numeric_limits<double>::quiet_NaN();
  if (missed) {
    frame_error = std::numeric_limits<double>::infinity();
  } else if (tips > 0) {
    frame_error = tip_error_sum / tips;
  }
  score_.per_frame_error_mm.push_back(frame_error);
  return match;
}

SequenceScore HandsScorer::finish(double tracking_seconds) {
  score_.posed_frames = score_.left_frames = score_.hand_known_frames = score_.hand_correct = 0;
  score_.identity_swaps = 0;
  score_.joints = {};
  for (auto& hand : score_.hands) {
    summarise(hand);
    hand.fps = tracking_seconds > 0.0 ? hand.frames / tracking_seconds : 0.0;
    score_.posed_frames += hand.posed_frames;
    score_.left_frames += hand.left_frames;
    score_.hand_known_frames += hand.hand_known_frames;
    score_.hand_correct += hand.hand_correct;
    score_.identity_swaps += hand.identity_swaps;
    score_.joints.add(hand.joints);
  }
  summarise(score_);
  score_.fps = tracking_seconds > 0.0 ? score_.frames / tracking_seconds : 0.0;
  return score_;
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
  std::snprintf(line, sizeof line, "%-14s %7s %9s %6s %6s %6s %6s %8s %7s %7s\n", "sequence", "frames", "mean_mm",
                "<15", "<20", "<25", "<30", "fps", "guided", "hand_%");
  text += line;
  // "-" for a figure over no frame: the mean where no annotated frame got a pose, the share of frames
  // reported as the hand shown where the sequences do not say which it is (hand.json).
  const auto figure = [](double value, const char* format) {
    char cell[32];
    if (!std::isfinite(value)) return std::string("-");
    std::snprintf(cell, sizeof cell, format, value);
    return std::string(cell);
  };
  const auto row = [&](const SequenceScore& s) {
    const double hand = s.hand_known_frames > 0 ? 100.0 * s.hand_correct / s.hand_known_frames
                                                : std::numeric_limits<double>::quiet_NaN();
    std::snprintf(line, sizeof line, "%-14s %7d %9s %6s %6s %6s %6s %8.1f %7d %7s\n", s.name.c_str(), s.frames,
                  figure(s.mean_error_mm, "%.2f").c_str(), figure(s.pct_below[0], "%.1f").c_str(),
                  figure(s.pct_below[1], "%.1f").c_str(), figure(s.pct_below[2], "%.1f").c_str(),
                  figure(s.pct_below[3], "%.1f").c_str(), s.fps, s.guided_wins, figure(hand, "%.1f").c_str());
    text += line;
  };
  for (const auto& s : sequences) row(s);
  row(total);
  for (const auto& g : groups) {
    text += "\nby " + g.by + ":\n";
    for (const auto& s : g.groups) row(s);
  }
  // Where sequences have joints.csv: the joint errors of the overall row and of each group's.
  if (total.joints.frames > 0) {
    std::snprintf(line, sizeof line, "\njoint error, mm (frames with a pose and joints.csv):\n%-14s %7s %9s", "pooled",
                  "frames", "all");
    text += line;
    for (const char* kind : kJointKinds) {
      std::snprintf(line, sizeof line, " %6s", kind);
      text += line;
    }
    text += '\n';
    const auto joint_row = [&](const SequenceScore& s) {
      std::snprintf(line, sizeof line, "%-14s %7d %9s", s.name.c_str(), s.joints.frames,
                    figure(s.joints.mean_mm(), "%.2f").c_str());
      text += line;
      for (size_t k = 0; k < kJointKinds.size(); ++k) {
        std::snprintf(line, sizeof line, " %6s", figure(s.joints.kind_mean_mm(k), "%.1f").c_str());
        text += line;
      }
      text += '\n';
    };
    joint_row(total);
    for (const auto& g : groups) {
      text += "by " + g.by + ":\n";
      for (const auto& s : g.groups) joint_row(s);
    }
  }
  // Scored per hand: a row per ground-truth hand (missed frames, the share reported on the right
  // side, identity swaps), and the phantom hands of the sequence.
  const bool per_hand = std::any_of(sequences.begin(), sequences.end(), [](const auto& s) { return !s.hands.empty(); });
  if (!per_hand) return text;
  std::snprintf(line, sizeof line, "\nper hand:\n%-22s %7s %9s %6s %6s %6s %6s %7s %7s %6s\n", "hand", "frames",
                "mean_mm", "<15", "<20", "<25", "<30", "missed", "side_%", "swaps");
  text += line;
  const auto hand_rows = [&](const SequenceScore& s) {
    if (s.hands.empty()) return;
    for (size_t k = 0; k < s.hands.size(); ++k) {
      const SequenceScore& h = s.hands[k];
      const std::string label = s.name + "/" + std::to_string(k) + " " +
                                (h.expected_hand ? to_string(*h.expected_hand) : "?");
      const double side = h.hand_known_frames > 0 ? 100.0 * h.hand_correct / h.hand_known_frames
                                                  : std::numeric_limits<double>::quiet_NaN();
      std::snprintf(line, sizeof line, "%-22s %7d %9s %6s %6s %6s %6s %7d %7s %6d\n", label.c_str(), h.frames,
                    figure(h.mean_error_mm, "%.2f").c_str(), figure(h.pct_below[0], "%.1f").c_str(),
                    figure(h.pct_below[1], "%.1f").c_str(), figure(h.pct_below[2], "%.1f").c_str(),
                    figure(h.pct_below[3], "%.1f").c_str(), h.without_pose, figure(side, "%.1f").c_str(),
                    h.identity_swaps);
      text += line;
    }
    std::snprintf(line, sizeof line, "  %s: %d frames with a phantom hand (%d hands)\n", s.name.c_str(),
                  s.phantom_frames, s.phantom_hands);
    text += line;
  };
  for (const auto& s : sequences) hand_rows(s);
  hand_rows(total);
  return text;
}

nlohmann::json to_json(const std::vector<SequenceScore>& sequences, const SequenceScore& total,
                       const std::vector<ScoreGroups>& groups) {
  const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  const auto pct = [&](const SequenceScore& s) {
    nlohmann::json j = nlohmann::json::object();
    for (size_t k = 0; k < kThresholdsMm.size(); ++k) j[std::to_string(kThresholdsMm[k])] = number(s.pct_below[k]);
    return j;
  };
  // Of the frames with a pose: the share reported left, and where the truth is known, right.
  const auto hands = [&](const SequenceScore& s) {
    const auto share = [&](int n, int of) { return of > 0 ? number(100.0 * n / of) : nlohmann::json(nullptr); };
    nlohmann::json j = {{"frames_with_pose", s.posed_frames},
                        {"pct_frames_left", share(s.left_frames, s.posed_frames)},
                        {"pct_frames_correct", share(s.hand_correct, s.hand_known_frames)}};
    if (s.expected_hand) j["expected"] = to_string(*s.expected_hand);
    return j;
  };
  // The frames scored on their joints, the mean over all 21 and over each kind's (null: none).
  const auto joint_scores = [&](const JointErrors& e) {
    nlohmann::json by_kind = nlohmann::json::object();
    for (size_t k = 0; k < kJointKinds.size(); ++k) by_kind[kJointKinds[k]] = number(e.kind_mean_mm(k));
    return nlohmann::json{{"frames_scored", e.frames}, {"mean_error_mm", number(e.mean_mm())},
                          {"mean_error_by_kind_mm", by_kind}};
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
                          {"joints", joint_scores(s.joints)},
                          {"fps", s.fps}};
  };
  // Scored per hand: each ground-truth hand's scores, its misses and identity swaps (also per 1000
  // of the sequence's frames), and the sequence's phantom hands. Nothing for a one-hand scoring.
  const auto add_hands = [&](nlohmann::json& j, const SequenceScore& s) {
    if (s.hands.empty()) return;
    j["hands"] = nlohmann::json::array();
    for (size_t k = 0; k < s.hands.size(); ++k) {
      const SequenceScore& h = s.hands[k];
      nlohmann::json hand = {{"hand", k},
                             {"side", h.expected_hand ? nlohmann::json(to_string(*h.expected_hand)) : nlohmann::json(nullptr)},
                             {"misses", h.without_pose},
                             {"identity_swaps", h.identity_swaps},
                             {"identity_swaps_per_1000_frames", h.frames > 0 ? number(1000.0 * h.identity_swaps / h.frames)
                                                                             : nlohmann::json(nullptr)}};
      hand.update(scores(h));
      j["hands"].push_back(std::move(hand));
    }
    j["identity_swaps"] = s.identity_swaps;
    j["phantom_frames"] = s.phantom_frames;
    j["phantom_hands"] = s.phantom_hands;
    j["pct_frames_with_phantom"] = s.frames > 0 ? number(100.0 * s.phantom_frames / s.frames) : nlohmann::json(nullptr);
  };
  nlohmann::json out;
  out["sequences"] = nlohmann::json::array();
  for (const auto& s : sequences) {
    nlohmann::json j = {{"name", s.name}};
    j.update(scores(s));
    if (!s.view.empty()) j["view"] = s.view;
    if (!s.motion.empty()) j["motion"] = s.motion;
    add_hands(j, s);
    out["sequences"].push_back(std::move(j));
  }
  out["overall"] = scores(total);
  add_hands(out["overall"], total);
  if (!groups.empty()) {
    out["groups"] = nlohmann::json::object();
    for (const auto& g : groups) {
      for (const auto& s : g.groups) out["groups"][g.by][s.name] = scores(s);
    }
  }
  return out;
}

}  // namespace handtrack::eval
