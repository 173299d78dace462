#pragma once
// hand_slots.hpp (private): per-hand state kept across frames and matched to a frame's hands by
// hand_id, for the C API's filter and gestures. A state with hand_id 0 is free. There are
// HANDTRACK_MAX_HANDS states: a caller first frees the states of hands missing from the frame
// (frame_has_hand), so every hand of the frame then finds its own state or a free one.
//
// Thread roles: reentrant (plain functions on the caller's states).
#include <handtrack/client.h>

#include <algorithm>
#include <array>
#include <cstdint>

namespace handtrack::ipc::detail {

// The frame's hands that count: hands[0 .. hand_count-1], never past the record.
inline std::uint32_t hand_count(const handtrack_frame& frame) noexcept {
  return std::min<std::uint32_t>(frame.hand_count, HANDTRACK_MAX_HANDS);
}

inline bool frame_has_hand(const handtrack_frame& frame, std::uint32_t hand_id) noexcept {
  const std::uint32_t count = hand_count(frame);
  for (std::uint32_t i = 0; i < count; ++i) {
    if (frame.hands[i].hand_id == hand_id) return true;
  }
  return false;
}

// The state of `hand_id` (not 0): its own, or a free one started afresh (State{}) for a new hand.
template <typename State>
State& hand_state(std::array<State, HANDTRACK_MAX_HANDS>& states, std::uint32_t hand_id) noexcept {
  State* free_state = nullptr;
  for (State& s : states) {
    if (s.hand_id == hand_id) return s;
    if (s.hand_id == 0 && free_state == nullptr) free_state = &s;
  }
  *free_state = State{};
  free_state->hand_id = hand_id;
  return *free_state;
}

}  // namespace handtrack::ipc::detail
