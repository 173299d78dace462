// The client library's gestures (handtrack_gesture*, docs/GESTURES.md) on hands built joint by
// joint: an open hand, a fist, a pointing hand and a pinch give the strengths they should, and
// start/end events follow the hysteresis (and a lost hand ends what was on), for each hand of a
// frame on its own.
#include <handtrack/client.h>
#include <handtrack/client.hpp>

#include <gtest/gtest.h>

#include <cstring>
#include <initializer_list>

namespace {

enum class Finger { kStraight, kCurled };

// A right hand seen by the camera, palm toward it: the wrist below, each finger's base 60 mm
// above it (the thumb's lower and further out), straight fingers pointing up (-y; a straight thumb
// points sideways, -x), curled ones bent 90 degrees twice toward the camera.
handtrack_hand hand(Finger thumb, Finger index, Finger middle, Finger ring, Finger little) {
  handtrack_hand p{};
  p.hand_id = 1;
  p.handedness = HANDTRACK_HANDEDNESS_RIGHT;
  p.state = HANDTRACK_STATE_TRACKING;
  const float z = 400.0F;
  p.joints_mm[0][0] = 0.0F, p.joints_mm[0][1] = 0.0F, p.joints_mm[0][2] = z;
  const Finger fingers[5] = {thumb, index, middle, ring, little};
  for (int f = 0; f < 5; ++f) {
    const float base[3] = {f == 0 ? -60.0F : -40.0F + 20.0F * static_cast<float>(f), f == 0 ? -20.0F : -60.0F, z};
    const float bones[3] = {40.0F, 25.0F, 20.0F};
    float at[3] = {base[0], base[1], base[2]};
    for (int k = 0; k < 4; ++k) {
      if (k > 0) {
        const float len = bones[k - 1];
        if (fingers[f] == Finger::kStraight && f == 0) {
          at[0] -= len;
        } else if (fingers[f] == Finger::kStraight || k == 1) {
          at[1] -= len;
        } else if (k == 2) {
          at[2] -= len;  // toward the camera
        } else {
          at[1] += len;  // back down, into the palm
        }
      }
      std::memcpy(p.joints_mm[1 + 4 * f + k], at, sizeof at);
    }
    std::memcpy(p.fingertips_mm[f], p.joints_mm[1 + 4 * f + 3], sizeof at);
  }
  return p;
}

constexpr auto S = Finger::kStraight;
constexpr auto C = Finger::kCurled;

std::array<float, HANDTRACK_NUM_GESTURES> strengths(const handtrack_hand& p) {
  std::array<float, HANDTRACK_NUM_GESTURES> s{};
  handtrack_gesture_strengths(&p, s.data());
  return s;
}

TEST(Gestures, StrengthsOfKnownHands) {
  const auto open = strengths(hand(S, S, S, S, S));
  EXPECT_EQ(open[HANDTRACK_GESTURE_GRAB], 0.0F);
  EXPECT_EQ(open[HANDTRACK_GESTURE_POINT], 0.0F);
  EXPECT_EQ(open[HANDTRACK_GESTURE_PINCH], 0.0F) << "the thumb stands out sideways";

  const auto fist = strengths(hand(C, C, C, C, C));
  EXPECT_EQ(fist[HANDTRACK_GESTURE_GRAB], 1.0F);
  EXPECT_EQ(fist[HANDTRACK_GESTURE_POINT], 0.0F) << "the index is curled too";

  const auto point = strengths(hand(C, S, C, C, C));
  EXPECT_EQ(point[HANDTRACK_GESTURE_POINT], 1.0F);
  EXPECT_LT(point[HANDTRACK_GESTURE_GRAB], HANDTRACK_GESTURE_ON) << "pointing is not grabbing";

  handtrack_hand pinch = hand(S, S, S, S, S);
  std::memcpy(pinch.fingertips_mm[0], pinch.fingertips_mm[1], sizeof pinch.fingertips_mm[0]);
  pinch.fingertips_mm[0][0] -= 15.0F;  // tip centres 15 mm apart: touching
  EXPECT_EQ(strengths(pinch)[HANDTRACK_GESTURE_PINCH], 1.0F);
  pinch.fingertips_mm[0][0] -= 25.0F;  // 40 mm: halfway between closed (20) and open (60)
  EXPECT_NEAR(strengths(pinch)[HANDTRACK_GESTURE_PINCH], 0.5F, 1e-5);

  handtrack_hand lost = hand(C, C, C, C, C);
  lost.state = HANDTRACK_STATE_NO_HAND;
  EXPECT_EQ(strengths(lost)[HANDTRACK_GESTURE_GRAB], 0.0F) << "no hand, no gesture";
}

// A hand whose index and middle..little curl by `amount` (0 open .. 1 fist), by moving the tips
// between the straight and the curled places.
handtrack_hand partly_curled(float amount) {
  handtrack_hand open = hand(S, S, S, S, S);
  const handtrack_hand fist = hand(S, C, C, C, C);
  for (int j = 0; j < HANDTRACK_NUM_JOINTS; ++j) {
    for (int k = 0; k < 3; ++k) open.joints_mm[j][k] += amount * (fist.joints_mm[j][k] - open.joints_mm[j][k]);
  }
  return open;
}

// A frame holding `hands`.
handtrack_frame frame_of(std::initializer_list<handtrack_hand> hands) {
  handtrack_frame f{};
  for (const handtrack_hand& h : hands) f.hands[f.hand_count++] = h;
  return f;
}

TEST(Gestures, EventsFollowTheHysteresis) {
  handtrack::Gestures gestures;
  // Grab strength up through ON, jittering in the band, down through OFF.
  const float amounts[] = {0.0F, 0.5F, 1.0F, 0.8F, 1.0F, 0.75F, 0.3F, 0.0F, 1.0F};
  std::vector<int> events;
  std::vector<float> grab;
  for (const float a : amounts) {
    const auto& states = gestures.update(frame_of({partly_curled(a)}));
    ASSERT_EQ(states.size(), 1U);
    const handtrack_gesture_state& g = states[0];
    EXPECT_EQ(g.hand_id, 1U);
    EXPECT_EQ(g.present, 1);
    grab.push_back(g.strength[HANDTRACK_GESTURE_GRAB]);
    events.push_back(g.event[HANDTRACK_GESTURE_GRAB]);
  }
  // Check against the strengths themselves: a start when crossing above ON while off, an end when
  // falling below OFF while on, nothing in between.
  bool on = false;
  int starts = 0;
  for (size_t i = 0; i < grab.size(); ++i) {
    int expected = HANDTRACK_GESTURE_NONE;
    if (!on && grab[i] > HANDTRACK_GESTURE_ON) expected = HANDTRACK_GESTURE_START, on = true, ++starts;
    else if (on && grab[i] < HANDTRACK_GESTURE_OFF) expected = HANDTRACK_GESTURE_END, on = false;
    EXPECT_EQ(events[i], expected) << "step " << i << ", strength " << grab[i];
  }
  EXPECT_EQ(starts, 2) << "two grabs: jitter inside the band is not a new one";

  // Losing the hand (a frame without it) ends an active gesture at once.
  EXPECT_EQ(gestures.states()[0].active[HANDTRACK_GESTURE_GRAB], 1);
  const auto& after = gestures.update(frame_of({}));
  ASSERT_EQ(after.size(), 1U) << "the hand that left is reported";
  EXPECT_EQ(after[0].hand_id, 1U);
  EXPECT_EQ(after[0].handedness, HANDTRACK_HANDEDNESS_RIGHT);
  EXPECT_EQ(after[0].present, 0);
  EXPECT_EQ(after[0].event[HANDTRACK_GESTURE_GRAB], HANDTRACK_GESTURE_END);
  EXPECT_EQ(after[0].active[HANDTRACK_GESTURE_GRAB], 0);
  EXPECT_EQ(gestures.update(frame_of({})).size(), 0U) << "reported once";
}

// Two hands: each has its own hysteresis, found by hand_id wherever it is in hands[]; one that
// leaves ends its gestures while the other's go on; a new hand starts with nothing on.
TEST(Gestures, EachHandHasItsOwnGestures) {
  handtrack::Gestures gestures;
  handtrack_hand fist = hand(C, C, C, C, C);
  handtrack_hand open = hand(S, S, S, S, S);
  open.hand_id = 2;
  open.handedness = HANDTRACK_HANDEDNESS_LEFT;
  const auto& first = gestures.update(frame_of({fist, open}));
  ASSERT_EQ(first.size(), 2U);
  EXPECT_EQ(first[0].hand_id, 1U);
  EXPECT_EQ(first[0].event[HANDTRACK_GESTURE_GRAB], HANDTRACK_GESTURE_START);
  EXPECT_EQ(first[1].hand_id, 2U);
  EXPECT_EQ(first[1].handedness, HANDTRACK_HANDEDNESS_LEFT);
  EXPECT_EQ(first[1].active[HANDTRACK_GESTURE_GRAB], 0);

  // The open hand makes a fist, now listed first: hand 1's grab goes on, hand 2's starts.
  handtrack_hand second_fist = hand(C, C, C, C, C);
  second_fist.hand_id = 2;
  const auto& both = gestures.update(frame_of({second_fist, fist}));
  ASSERT_EQ(both.size(), 2U);
  EXPECT_EQ(both[0].hand_id, 2U);
  EXPECT_EQ(both[0].event[HANDTRACK_GESTURE_GRAB], HANDTRACK_GESTURE_START);
  EXPECT_EQ(both[1].hand_id, 1U);
  EXPECT_EQ(both[1].event[HANDTRACK_GESTURE_GRAB], HANDTRACK_GESTURE_NONE);
  EXPECT_EQ(both[1].active[HANDTRACK_GESTURE_GRAB], 1);

  // Hand 2 leaves and hand 3 (a fist) comes in the same frame: hand 3 first, then hand 2's end.
  handtrack_hand third = hand(C, C, C, C, C);
  third.hand_id = 3;
  const auto& swap = gestures.update(frame_of({fist, third}));
  ASSERT_EQ(swap.size(), 3U);
  EXPECT_EQ(swap[0].hand_id, 1U);
  EXPECT_EQ(swap[0].event[HANDTRACK_GESTURE_GRAB], HANDTRACK_GESTURE_NONE);
  EXPECT_EQ(swap[1].hand_id, 3U);
  EXPECT_EQ(swap[1].event[HANDTRACK_GESTURE_GRAB], HANDTRACK_GESTURE_START) << "a new hand starts with nothing on";
  EXPECT_EQ(swap[2].hand_id, 2U);
  EXPECT_EQ(swap[2].present, 0);
  EXPECT_EQ(swap[2].event[HANDTRACK_GESTURE_GRAB], HANDTRACK_GESTURE_END);
}

TEST(Gestures, NamesAndArguments) {
  EXPECT_STREQ(handtrack_gesture_name(HANDTRACK_GESTURE_PINCH), "pinch");
  EXPECT_STREQ(handtrack_gesture_name(HANDTRACK_GESTURE_GRAB), "grab");
  EXPECT_STREQ(handtrack_gesture_name(HANDTRACK_GESTURE_POINT), "point");
  EXPECT_STREQ(handtrack_gesture_name(7), "unknown");
  handtrack_gesture_state states[HANDTRACK_GESTURE_MAX_STATES]{};
  EXPECT_EQ(handtrack_gestures_update(nullptr, nullptr, states), HANDTRACK_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(handtrack_gestures_new(nullptr), HANDTRACK_ERR_INVALID_ARGUMENT);
}

}  // namespace
