/*
 * handtrack/client.h: the stable C API for reading hand poses from handtrackd's shared memory.
 *
 * A client maps the daemon's POSIX shared-memory object read-only; it can never block or corrupt
 * the daemon. Typical use:
 *
 *     handtrack_client* c = NULL;
 *     int st = handtrack_open(NULL, &c);            // NULL = the default name "handtrack"
 *     if (st != HANDTRACK_OK) { fprintf(stderr, "%s\n", handtrack_strerror(st)); return 1; }
 *     handtrack_frame frame;
 *     for (;;) {
 *       st = handtrack_wait_next(c, &frame, 1000000000);   // wait at most 1 s
 *       if (st == HANDTRACK_OK)
 *         for (uint32_t i = 0; i < frame.hand_count; ++i) use(&frame.hands[i]);
 *       else if (st < 0 && st != HANDTRACK_ERR_WRITER_DEAD && st != HANDTRACK_ERR_WRITER_STOPPED) break;
 *     }
 *     handtrack_close(c);
 *
 * Status values: HANDTRACK_OK (0), positive "nothing yet" values (HANDTRACK_TIMEOUT,
 * HANDTRACK_NO_RECORD) and negative errors. No function throws, allocates after handtrack_open, or
 * blocks longer than its timeout.
 *
 * Thread roles: reentrant: one handtrack_client belongs to one thread at a time; distinct clients are
 * independent. handtrack_strerror and handtrack_abi_version are thread-safe.
 *
 * ABI: the record and header layouts are fixed for a given HANDTRACK_ABI_VERSION; a client refuses
 * a segment whose magic, ABI version, record size or layout differ (see docs/IPC.md). Version 2
 * (this one, libhandtrack_client.so.2) carries frames of up to HANDTRACK_MAX_HANDS hands, each
 * with its id and handedness; version 1 carried one pose per record.
 */
#ifndef HANDTRACK_CLIENT_H
#define HANDTRACK_CLIENT_H

#include <stddef.h>
#include <stdint.h>

#if defined(_WIN32)
#define HANDTRACK_API
#elif defined(HANDTRACK_CLIENT_BUILDING)
#define HANDTRACK_API __attribute__((visibility("default")))
#else
#define HANDTRACK_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Version of the shared-memory layout (header, slot and record). Bumped on any layout change. */
#define HANDTRACK_ABI_VERSION 2u
/* Default shared-memory object name (shm_open name without the leading slash). */
#define HANDTRACK_DEFAULT_SHM_NAME "handtrack"

#define HANDTRACK_NUM_PARAMS 26    /* pose parameters (paper: 26 degrees of freedom) */
#define HANDTRACK_NUM_JOINTS 21    /* wrist, then per finger thumb..little: MCP/CMC, PIP, DIP, TIP */
#define HANDTRACK_NUM_FINGERTIPS 5 /* thumb, index, middle, ring, little */
/* Hands a frame can hold (part of the ABI: the frame record holds this many hand records). */
#define HANDTRACK_MAX_HANDS 2

typedef enum handtrack_status {
  HANDTRACK_OK = 0,
  HANDTRACK_TIMEOUT = 1,   /* no new record within the timeout; the writer is alive */
  HANDTRACK_NO_RECORD = 2, /* the writer has not published any record yet */
  HANDTRACK_ERR_INVALID_ARGUMENT = -1,
  HANDTRACK_ERR_NOT_FOUND = -2,      /* no shared-memory object with that name (daemon not running) */
  HANDTRACK_ERR_PERMISSION = -3,     /* not allowed to open it (group membership?) */
  HANDTRACK_ERR_NOT_READY = -4,      /* the writer is still initializing the segment */
  HANDTRACK_ERR_BAD_MAGIC = -5,      /* not a handtrack segment */
  HANDTRACK_ERR_BAD_ENDIANNESS = -6, /* written by a machine of the other byte order */
  HANDTRACK_ERR_BAD_VERSION = -7,    /* different ABI version: rebuild the client */
  HANDTRACK_ERR_BAD_RECORD_SIZE = -8,
  HANDTRACK_ERR_BAD_LAYOUT = -9,     /* header sizes or capacity inconsistent */
  HANDTRACK_ERR_TRUNCATED = -10,     /* the object is smaller than its header says */
  HANDTRACK_ERR_WRITER_DEAD = -11,   /* heartbeat stale: the daemon died or hangs */
  HANDTRACK_ERR_WRITER_STOPPED = -12, /* the daemon stopped cleanly */
  HANDTRACK_ERR_BUSY = -13,          /* the writer overwrote the slot during every read attempt */
  HANDTRACK_ERR_SYSTEM = -14,        /* an unexpected system call failure (see handtrack_error_detail) */
  HANDTRACK_ERR_UNTRUSTED_OWNER = -15 /* the segment's owner is not trusted, or others may write it */
} handtrack_status;

typedef enum handtrack_tracking_state {
  HANDTRACK_STATE_NO_HAND = 0,
  HANDTRACK_STATE_TRACKING = 1,
  HANDTRACK_STATE_RECOVERING = 2
} handtrack_tracking_state;

typedef enum handtrack_device_state {
  HANDTRACK_DEVICE_STOPPED = 0,            /* writer exited cleanly (or never started streaming) */
  HANDTRACK_DEVICE_STARTING = 1,           /* segment created, source being opened */
  HANDTRACK_DEVICE_WAITING_FOR_DEVICE = 2, /* no camera yet: waiting for one to be plugged in */
  HANDTRACK_DEVICE_STREAMING = 3,          /* frames are flowing */
  HANDTRACK_DEVICE_ERROR = 4               /* the source failed; the daemon keeps retrying */
} handtrack_device_state;

/* Which hand a hand record is of. A present hand is left or right; "unknown" is for a record
 * without a hand (and for a tracker that cannot tell, should one ever publish that). */
typedef enum handtrack_handedness {
  HANDTRACK_HANDEDNESS_UNKNOWN = 0,
  HANDTRACK_HANDEDNESS_LEFT = 1,
  HANDTRACK_HANDEDNESS_RIGHT = 2
} handtrack_handedness;

/*
 * One hand of a frame: 640 bytes, trivially copyable, fixed-width fields, no implicit padding,
 * native byte order. Positions are millimetres in the camera frame (x right, y down, z forward).
 */
typedef struct handtrack_hand {
  uint32_t hand_id;            /* stable while the hand stays in view; never 0 for a present hand;
                                  a hand that leaves and comes back gets a new id */
  int32_t handedness;          /* handtrack_handedness */
  float handedness_confidence; /* 0..1: how clearly the tracker told left from right */
  int32_t state;               /* handtrack_tracking_state */
  float confidence;            /* 0..1 */
  float energy;                /* final value of the optimized energy (lower is better) */
  float optimize_ms;           /* this hand's optimization (the frame's optimize_ms spans all hands) */
  uint32_t flags;              /* reserved, 0 */
  /* The 26 pose parameters as the tracker optimizes them (double: the optimizer's precision,
   * round-trips exactly): params[0..2] global translation mm, params[3..5] global rotation rad,
   * params[6..25] joint angles rad (see docs/IPC.md for the order). */
  double params[HANDTRACK_NUM_PARAMS];
  float joints_mm[HANDTRACK_NUM_JOINTS][3];
  float fingertips_mm[HANDTRACK_NUM_FINGERTIPS][3]; /* thumb, index, middle, ring, little */
  float palm_center_mm[3];
  float palm_normal[3];        /* unit vector, pointing out of the palm */
  float pinch_distance_mm;     /* thumb tip to index tip */
  float pinch_strength;        /* 0 (open) .. 1 (touching) */
  float hand_scale[3];         /* hand-model scale factors: length, width, Gaussian sigma (1 = default) */
  uint32_t reserved[11];       /* 0; pads the hand to 640 bytes (room for per-hand fields) */
} handtrack_hand;

/*
 * One frame: 1336 bytes, the unit a reader gets. Every hand of the frame is in it, read together
 * under one sequence counter, so a reader never sees hands of two different frames. hands[0 ..
 * hand_count-1] are the hands seen (hand_count 0: no hand in this frame); the rest are zero.
 * Times are CLOCK_MONOTONIC nanoseconds of the machine running the daemon.
 */
typedef struct handtrack_frame {
  uint64_t frame;      /* daemon frame number (counts grabbed frames within an epoch) */
  uint64_t epoch;      /* writer epoch: grows with each daemon start (stamped by the writer) */
  int64_t capture_ns;  /* when the depth frame was captured */
  int64_t publish_ns;  /* when the record was published (stamped by the writer) */
  float grab_ms;       /* per-stage timings of this frame */
  float preprocess_ms;
  float optimize_ms;   /* all hands (each hand has its own optimize_ms too) */
  float publish_ms;
  uint32_t hand_count; /* 0..HANDTRACK_MAX_HANDS */
  uint32_t flags;      /* reserved, 0 */
  handtrack_hand hands[HANDTRACK_MAX_HANDS];
} handtrack_frame;

/* Live statistics of the daemon, refreshed about once a second. */
typedef struct handtrack_stats {
  float fps;                /* published frames per second */
  float grab_ms;            /* mean per-stage times over the last interval */
  float preprocess_ms;
  float optimize_ms;
  float publish_ms;
  float latency_p50_ms;     /* capture to publish */
  float latency_p99_ms;
  uint32_t reserved;
  uint64_t frames_captured; /* since the daemon started */
  uint64_t frames_dropped;  /* captured but never processed (the pipeline was busy) */
  uint64_t frames_skipped;  /* processed but not published (e.g. invalid depth) */
  uint64_t source_errors;   /* failures reported by the depth source */
} handtrack_stats;

typedef struct handtrack_writer_status {
  int32_t device_state;      /* handtrack_device_state */
  int32_t alive;             /* 1 if the heartbeat is fresh and the writer has not stopped */
  int32_t writer_pid;        /* in the writer's pid namespace */
  uint32_t capacity;         /* records in the ring */
  uint64_t epoch;
  uint64_t records_published; /* in this epoch */
  int64_t heartbeat_ns;       /* CLOCK_MONOTONIC of the last heartbeat */
  int64_t heartbeat_age_ns;   /* now - heartbeat_ns, as seen by this client */
  int64_t heartbeat_period_ns;
  handtrack_stats stats;
} handtrack_writer_status;

/* The layout is part of the ABI: these sizes never change within one HANDTRACK_ABI_VERSION. */
#if defined(__cplusplus)
static_assert(sizeof(handtrack_hand) == 640, "handtrack_hand layout changed");
static_assert(sizeof(handtrack_frame) == 1336, "handtrack_frame layout changed");
static_assert(sizeof(handtrack_stats) == 64, "handtrack_stats layout changed");
static_assert(sizeof(handtrack_writer_status) == 120, "handtrack_writer_status layout changed");
#elif defined(__STDC_VERSION__) && __STDC_VERSION__ >= 201112L
_Static_assert(sizeof(handtrack_hand) == 640, "handtrack_hand layout changed");
_Static_assert(sizeof(handtrack_frame) == 1336, "handtrack_frame layout changed");
_Static_assert(sizeof(handtrack_stats) == 64, "handtrack_stats layout changed");
_Static_assert(sizeof(handtrack_writer_status) == 120, "handtrack_writer_status layout changed");
#endif

typedef struct handtrack_client handtrack_client; /* opaque */

/* Opens (maps read-only) the segment `shm_name` (NULL: "handtrack"). On success *out is a client
 * that must be closed with handtrack_close. Only a segment owned by a trusted user (root, this
 * process's effective user, the service user "handtrack", and the users named in the environment
 * variable HANDTRACK_TRUSTED_USERS: comma-separated names or uids) and writable by its owner alone
 * is accepted; any other gives HANDTRACK_ERR_UNTRUSTED_OWNER, and handtrack_error_detail names the
 * owner. The same check applies when a waiting call reattaches to a new segment of that name. Waiting for records starts after the newest record
 * present at open time. On failure *out is NULL and the status says why. */
HANDTRACK_API int handtrack_open(const char* shm_name, handtrack_client** out);
HANDTRACK_API void handtrack_close(handtrack_client* client);

/* Copies the newest frame, every hand of it. HANDTRACK_NO_RECORD if none was published yet. Never
 * blocks. */
HANDTRACK_API int handtrack_latest(handtrack_client* client, handtrack_frame* out);

/* Waits at most timeout_ns (0: do not wait) for the next record after the last one returned and
 * copies it. Records are returned in order; records overwritten before they could be read are
 * counted by handtrack_missed. If the writer dies or stops, returns HANDTRACK_ERR_WRITER_DEAD or
 * _STOPPED once, as soon as it is seen (within 3 heartbeat periods); later calls wait for a new
 * writer, reattach to it by themselves and continue with its records (a new epoch). */
HANDTRACK_API int handtrack_wait_next(handtrack_client* client, handtrack_frame* out, int64_t timeout_ns);

/* Like handtrack_wait_next but returns the newest record, skipping (and counting) older ones. */
HANDTRACK_API int handtrack_wait_latest(handtrack_client* client, handtrack_frame* out, int64_t timeout_ns);

/* The next handtrack_wait_next returns the oldest record still in the ring instead of the next new
 * one: what a client that attached late (a short recording played --fast) reads from. */
HANDTRACK_API int handtrack_rewind(handtrack_client* client);

/* Records skipped just before the record returned by the last successful read, and since open. */
HANDTRACK_API uint64_t handtrack_missed(const handtrack_client* client);
HANDTRACK_API uint64_t handtrack_missed_total(const handtrack_client* client);

/* The writer's state, epoch, heartbeat and live statistics. */
HANDTRACK_API int handtrack_writer_status_get(handtrack_client* client, handtrack_writer_status* out);

/* A constant English sentence for a status value. */
HANDTRACK_API const char* handtrack_strerror(int status);
/* Details of the last failure in this thread (e.g. the sizes that did not match); never NULL. */
HANDTRACK_API const char* handtrack_error_detail(void);
/* "no_hand", "tracking", "recovering" (or "unknown"). */
HANDTRACK_API const char* handtrack_state_name(int32_t tracking_state);
/* "left", "right" (or "unknown"). */
HANDTRACK_API const char* handtrack_handedness_name(int32_t handedness);
/* "stopped", "starting", "waiting_for_device", "streaming", "error" (or "unknown"). */
HANDTRACK_API const char* handtrack_device_state_name(int32_t device_state);

/*
 * Smoothing: a One Euro filter (Casiez, Roussel, Vogel, CHI 2012) on every point of every hand of
 * a frame (the 21 joints, 5 fingertips, palm centre and palm normal; params and the pinch fields
 * are left as published). Each point is smoothed by an exponential filter whose cutoff frequency
 * grows with the point's speed: f_c = min_cutoff_hz + beta * speed (mm/s), so a still hand loses
 * its jitter and a moving one keeps up. One filter follows all the hands of a stream of frames,
 * each by its hand_id: a hand keeps its own history while it stays in view, a new hand_id starts
 * afresh, and the history of a hand missing from a frame is dropped. A hand starts afresh (passes
 * through unchanged) on a new epoch (a restarted daemon), after a gap longer than max_gap_s, when
 * capture time goes backwards, and while its state is not "tracking". Typical use:
 *
 *     handtrack_filter* f = NULL;
 *     handtrack_filter_new(NULL, &f);               // NULL: the defaults below
 *     ... handtrack_wait_next(c, &frame, ...); handtrack_filter_apply(f, &frame); use(&frame); ...
 *     handtrack_filter_free(f);
 *
 * The defaults were chosen on the synthetic motions at 60 fps: the least fingertip jitter for at
 * most one frame of added lag (docs/FILTER.md has the table). Thread roles: reentrant: one filter
 * per stream of frames, used by one thread at a time.
 */
#define HANDTRACK_FILTER_DEFAULT_MIN_CUTOFF_HZ 1.0
#define HANDTRACK_FILTER_DEFAULT_BETA 0.05
#define HANDTRACK_FILTER_DEFAULT_D_CUTOFF_HZ 1.0
#define HANDTRACK_FILTER_DEFAULT_MAX_GAP_S 0.25

typedef struct handtrack_filter_params {
  double min_cutoff_hz; /* cutoff of a still point, Hz: lower is smoother, and slower */
  double beta;          /* cutoff gained per mm/s of speed: higher follows fast moves closer */
  double d_cutoff_hz;   /* cutoff of the speed estimate, Hz */
  double max_gap_s;     /* a longer gap between two frames starts a hand's filter afresh */
} handtrack_filter_params;

typedef struct handtrack_filter handtrack_filter; /* opaque */

HANDTRACK_API void handtrack_filter_default_params(handtrack_filter_params* out);
/* params NULL: the defaults. HANDTRACK_ERR_INVALID_ARGUMENT for non-finite or non-positive
 * cutoffs or gap, or a negative beta. */
HANDTRACK_API int handtrack_filter_new(const handtrack_filter_params* params, handtrack_filter** out);
HANDTRACK_API void handtrack_filter_free(handtrack_filter* filter);
HANDTRACK_API void handtrack_filter_reset(handtrack_filter* filter);
/* Smooths every hand of `frame` in place (times from its capture_ns). Frames in order. Never
 * allocates. */
HANDTRACK_API int handtrack_filter_apply(handtrack_filter* filter, handtrack_frame* frame);

/*
 * Gestures (docs/GESTURES.md): from each hand's pose, a strength 0..1 for each gesture, and
 * start/end events with hysteresis: a gesture starts when its strength rises above
 * HANDTRACK_GESTURE_ON and ends when it falls below HANDTRACK_GESTURE_OFF or the hand is lost.
 *   pinch  thumb and index tips together (1 at 20 mm between the tip centres, 0 from 60 mm)
 *   grab   the fingers curled into a fist (middle..little weigh 3/4, the index 1/4)
 *   point  the index extended while middle..little are curled
 * A finger's curl is its reach (base to tip) over its length along the bones, from 0.95 (0) to
 * 0.50 (1). One handtrack_gestures follows every hand of a stream of frames, each by its hand_id
 * (as the filter does); a hand missing from a frame has left, and its gestures end there:
 *
 *     handtrack_gesture_state g[HANDTRACK_GESTURE_MAX_STATES];
 *     int n = handtrack_gestures_update(gestures, &frame, g);
 *     for (int i = 0; i < n; ++i)
 *       if (g[i].event[HANDTRACK_GESTURE_PINCH] == HANDTRACK_GESTURE_START) click(g[i].hand_id);
 *
 * Thread roles: reentrant.
 */
typedef enum handtrack_gesture {
  HANDTRACK_GESTURE_PINCH = 0,
  HANDTRACK_GESTURE_GRAB = 1,
  HANDTRACK_GESTURE_POINT = 2
} handtrack_gesture;
#define HANDTRACK_NUM_GESTURES 3
#define HANDTRACK_GESTURE_ON 0.8f
#define HANDTRACK_GESTURE_OFF 0.5f

typedef enum handtrack_gesture_event {
  HANDTRACK_GESTURE_NONE = 0,
  HANDTRACK_GESTURE_START = 1,
  HANDTRACK_GESTURE_END = 2
} handtrack_gesture_event;

typedef struct handtrack_gesture_state {
  uint32_t hand_id;                       /* whose gestures these are */
  int32_t handedness;                     /* handtrack_handedness */
  int32_t present;                        /* 1: in this frame; 0: the hand left (its gestures end) */
  float strength[HANDTRACK_NUM_GESTURES]; /* 0..1, by handtrack_gesture */
  int32_t active[HANDTRACK_NUM_GESTURES]; /* 1 while the gesture is on */
  int32_t event[HANDTRACK_NUM_GESTURES];  /* handtrack_gesture_event of this update */
} handtrack_gesture_state;

/* One update reports each hand of the frame and each hand that left: at most twice
 * HANDTRACK_MAX_HANDS states. */
#define HANDTRACK_GESTURE_MAX_STATES (2 * HANDTRACK_MAX_HANDS)

typedef struct handtrack_gestures handtrack_gestures; /* opaque: the hysteresis of each hand */

/* The strengths of one hand, without state (all 0 for a hand in state no_hand). */
HANDTRACK_API void handtrack_gesture_strengths(const handtrack_hand* hand, float out[HANDTRACK_NUM_GESTURES]);
HANDTRACK_API int handtrack_gestures_new(handtrack_gestures** out);
HANDTRACK_API void handtrack_gestures_free(handtrack_gestures* gestures);
HANDTRACK_API void handtrack_gestures_reset(handtrack_gestures* gestures);
/* The next frame, in order: for each hand, the strengths, which gestures are on and what started or
 * ended. Fills out[0 .. hand_count-1] with the frame's hands (in the frame's order, present = 1),
 * then one state per hand of the previous update that is no longer there (present = 0, strengths 0,
 * its active gestures ended). Returns how many states it filled (0..HANDTRACK_GESTURE_MAX_STATES),
 * or HANDTRACK_ERR_INVALID_ARGUMENT. */
HANDTRACK_API int handtrack_gestures_update(handtrack_gestures* gestures, const handtrack_frame* frame,
                                            handtrack_gesture_state out[HANDTRACK_GESTURE_MAX_STATES]);
/* "pinch", "grab", "point" (or "unknown"). */
HANDTRACK_API const char* handtrack_gesture_name(int gesture);

/* What the library was built with, for bindings to check their layout against. */
HANDTRACK_API uint32_t handtrack_abi_version(void);
HANDTRACK_API size_t handtrack_frame_size(void);
HANDTRACK_API size_t handtrack_hand_size(void);
HANDTRACK_API size_t handtrack_writer_status_size(void);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* HANDTRACK_CLIENT_H */
