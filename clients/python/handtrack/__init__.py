"""handtrack: read hand poses published by handtrackd, from Python.

A thin ctypes binding over the stable C library (libhandtrack_client.so.2, handtrack/client.h):
the same read-only mapping, seqlock and futex wait as C and C++ clients. The record layouts
below mirror ``handtrack_frame`` and ``handtrack_hand`` (shared-memory ABI version 2); at import
the module checks the library's ABI version and record sizes against them and refuses to load on
a mismatch.

    import handtrack
    with handtrack.Client("handtrack") as client:
        frame = client.wait_next(timeout=1.0)       # None on timeout
        if frame is not None:
            for hand in frame.hands:                # every hand of that frame ([] when none)
                print(frame.frame, hand.hand_id, hand.handedness, hand.state_name, hand.fingertips_mm[1][:])

The library is found through $HANDTRACK_CLIENT_LIB, then the system's library path.

Iterating: ``for frame in client.frames(): ...`` (or ``async for frame in client.aframes()`` in
asyncio code). With NumPy installed, ``hand.joints``, ``hand.fingertips`` and ``hand.pose_params``
are arrays (21x3, 5x3, 26); without it, lists. Smoothing (``PoseFilter``) and gestures
(``Gestures``) come from the C library and follow each hand by its ``hand_id``.
"""

import asyncio
import ctypes
import ctypes.util
import os
import time

try:
    import numpy as _np
except ImportError:  # NumPy is optional: lists instead of arrays
    _np = None

__version__ = "0.1.0"

__all__ = ["Client", "Frame", "Hand", "Stats", "WriterStatus", "HandtrackError", "ABI_VERSION",
           "TIMEOUT", "NO_RECORD", "ERR_WRITER_DEAD", "ERR_WRITER_STOPPED",
           "ERR_UNTRUSTED_OWNER", "PoseFilter", "FilterParams", "Gestures", "GESTURE_NAMES"]

ABI_VERSION = 2
MAX_HANDS = 2
NUM_PARAMS = 26
NUM_JOINTS = 21
NUM_FINGERTIPS = 5

OK = 0
TIMEOUT = 1
NO_RECORD = 2
ERR_NOT_FOUND = -2  # no segment of that name (the daemon has not started)
ERR_NOT_READY = -4  # the daemon is still creating it
ERR_WRITER_DEAD = -11
ERR_WRITER_STOPPED = -12
ERR_UNTRUSTED_OWNER = -15  # the segment's owner is not trusted (HANDTRACK_TRUSTED_USERS)

_Vec3 = ctypes.c_float * 3


class Hand(ctypes.Structure):
    """One hand of a frame; same layout as handtrack_hand (640 bytes)."""
    _fields_ = [
        ("hand_id", ctypes.c_uint32),
        ("handedness_code", ctypes.c_int32),
        ("handedness_confidence", ctypes.c_float),
        ("state", ctypes.c_int32),
        ("confidence", ctypes.c_float),
        ("energy", ctypes.c_float),
        ("optimize_ms", ctypes.c_float),
        ("flags", ctypes.c_uint32),
        ("params", ctypes.c_double * NUM_PARAMS),
        ("joints_mm", _Vec3 * NUM_JOINTS),
        ("fingertips_mm", _Vec3 * NUM_FINGERTIPS),
        ("palm_center_mm", _Vec3),
        ("palm_normal", _Vec3),
        ("pinch_distance_mm", ctypes.c_float),
        ("pinch_strength", ctypes.c_float),
        ("hand_scale", ctypes.c_float * 3),
        ("reserved", ctypes.c_uint32 * 11),
    ]

    STATE_NAMES = {0: "no_hand", 1: "tracking", 2: "recovering"}
    HANDEDNESS_NAMES = {1: "left", 2: "right"}  # handtrack_handedness; 0 is "unknown"

    @property
    def handedness(self):
        """"left" or "right" ("unknown" only for a record without a hand)."""
        return self.HANDEDNESS_NAMES.get(self.handedness_code, "unknown")

    @property
    def joints(self):
        """The 21 joints (mm, camera frame): a 21x3 NumPy array, or a list of [x, y, z]."""
        return _array(self.joints_mm)

    @property
    def fingertips(self):
        """The 5 fingertips, thumb to little: a 5x3 NumPy array, or a list of [x, y, z]."""
        return _array(self.fingertips_mm)

    @property
    def pose_params(self):
        """The 26 pose parameters: a NumPy array, or a list."""
        return _array(self.params)

    @property
    def state_name(self):
        return self.STATE_NAMES.get(self.state, "unknown")

    def to_dict(self):
        """The fields handtrack-cat prints for a hand, as plain Python values."""
        return {
            "hand_id": self.hand_id, "handedness": self.handedness,
            "handedness_confidence": self.handedness_confidence, "state": self.state_name,
            "confidence": self.confidence, "energy": self.energy,
            "params": list(self.params),
            "joints": [list(j) for j in self.joints_mm],
            "fingertips": [list(t) for t in self.fingertips_mm],
            "pinch": {"distance_mm": self.pinch_distance_mm, "strength": self.pinch_strength},
        }


class Frame(ctypes.Structure):
    """One frame with every hand in it; same layout as handtrack_frame (1336 bytes). All its
    hands were read together: they belong to this frame."""
    _fields_ = [
        ("frame", ctypes.c_uint64),
        ("epoch", ctypes.c_uint64),
        ("capture_ns", ctypes.c_int64),
        ("publish_ns", ctypes.c_int64),
        ("grab_ms", ctypes.c_float),
        ("preprocess_ms", ctypes.c_float),
        ("optimize_ms", ctypes.c_float),
        ("publish_ms", ctypes.c_float),
        ("hand_count", ctypes.c_uint32),
        ("flags", ctypes.c_uint32),
        ("hand_records", Hand * MAX_HANDS),
    ]

    @property
    def hands(self):
        """The hands seen in this frame (an empty list when none), as Hand objects."""
        return [self.hand_records[i] for i in range(min(self.hand_count, MAX_HANDS))]

    def to_dict(self):
        """The fields handtrack-cat prints (without "missed"), as plain Python values."""
        return {
            "frame": self.frame, "epoch": self.epoch,
            "capture_ns": self.capture_ns, "publish_ns": self.publish_ns,
            "hands": [hand.to_dict() for hand in self.hands],
        }


def _array(field):
    """A copy of a ctypes array field: a NumPy array when NumPy is there, else nested lists."""
    if _np is not None:
        return _np.ctypeslib.as_array(field).copy()
    return [list(row) if hasattr(row, "__len__") else row for row in field]


class Stats(ctypes.Structure):
    _fields_ = [
        ("fps", ctypes.c_float), ("grab_ms", ctypes.c_float), ("preprocess_ms", ctypes.c_float),
        ("optimize_ms", ctypes.c_float), ("publish_ms", ctypes.c_float),
        ("latency_p50_ms", ctypes.c_float), ("latency_p99_ms", ctypes.c_float),
        ("reserved", ctypes.c_uint32),
        ("frames_captured", ctypes.c_uint64), ("frames_dropped", ctypes.c_uint64),
        ("frames_skipped", ctypes.c_uint64), ("source_errors", ctypes.c_uint64),
    ]


class WriterStatus(ctypes.Structure):
    _fields_ = [
        ("device_state", ctypes.c_int32), ("alive", ctypes.c_int32),
        ("writer_pid", ctypes.c_int32), ("capacity", ctypes.c_uint32),
        ("epoch", ctypes.c_uint64), ("records_published", ctypes.c_uint64),
        ("heartbeat_ns", ctypes.c_int64), ("heartbeat_age_ns", ctypes.c_int64),
        ("heartbeat_period_ns", ctypes.c_int64), ("stats", Stats),
    ]


class HandtrackError(RuntimeError):
    """A negative status from the C library; .status holds it."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


def _load_library():
    candidates = []
    if os.environ.get("HANDTRACK_CLIENT_LIB"):
        candidates.append(os.environ["HANDTRACK_CLIENT_LIB"])
    found = ctypes.util.find_library("handtrack_client")
    if found:
        candidates.append(found)
    candidates.append("libhandtrack_client.so.2")
    errors = []
    for path in candidates:
        try:
            return ctypes.CDLL(path)
        except OSError as e:
            errors.append(f"{path}: {e}")
    raise ImportError("handtrack: cannot load libhandtrack_client.so (set HANDTRACK_CLIENT_LIB): "
                      + "; ".join(errors))


_lib = _load_library()
_lib.handtrack_abi_version.restype = ctypes.c_uint32
_lib.handtrack_frame_size.restype = ctypes.c_size_t
_lib.handtrack_hand_size.restype = ctypes.c_size_t
_lib.handtrack_writer_status_size.restype = ctypes.c_size_t
_lib.handtrack_open.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_void_p)]
_lib.handtrack_close.argtypes = [ctypes.c_void_p]
_lib.handtrack_close.restype = None
_lib.handtrack_latest.argtypes = [ctypes.c_void_p, ctypes.POINTER(Frame)]
_lib.handtrack_wait_next.argtypes = [ctypes.c_void_p, ctypes.POINTER(Frame), ctypes.c_int64]
_lib.handtrack_wait_latest.argtypes = [ctypes.c_void_p, ctypes.POINTER(Frame), ctypes.c_int64]
_lib.handtrack_missed.argtypes = [ctypes.c_void_p]
_lib.handtrack_missed.restype = ctypes.c_uint64
_lib.handtrack_missed_total.argtypes = [ctypes.c_void_p]
_lib.handtrack_missed_total.restype = ctypes.c_uint64
_lib.handtrack_writer_status_get.argtypes = [ctypes.c_void_p, ctypes.POINTER(WriterStatus)]
_lib.handtrack_strerror.argtypes = [ctypes.c_int]
_lib.handtrack_strerror.restype = ctypes.c_char_p
_lib.handtrack_error_detail.restype = ctypes.c_char_p


class FilterParams(ctypes.Structure):
    """handtrack_filter_params: the One Euro filter's parameters (docs/FILTER.md)."""
    _fields_ = [("min_cutoff_hz", ctypes.c_double), ("beta", ctypes.c_double),
                ("d_cutoff_hz", ctypes.c_double), ("max_gap_s", ctypes.c_double)]


_lib.handtrack_filter_default_params.argtypes = [ctypes.POINTER(FilterParams)]
_lib.handtrack_filter_default_params.restype = None
_lib.handtrack_filter_new.argtypes = [ctypes.POINTER(FilterParams), ctypes.POINTER(ctypes.c_void_p)]
_lib.handtrack_filter_free.argtypes = [ctypes.c_void_p]
_lib.handtrack_filter_free.restype = None
_lib.handtrack_filter_reset.argtypes = [ctypes.c_void_p]
_lib.handtrack_filter_reset.restype = None
_lib.handtrack_filter_apply.argtypes = [ctypes.c_void_p, ctypes.POINTER(Frame)]

NUM_GESTURES = 3
GESTURE_NAMES = ("pinch", "grab", "point")  # handtrack_gesture order


GESTURE_MAX_STATES = 2 * MAX_HANDS  # HANDTRACK_GESTURE_MAX_STATES


class GestureState(ctypes.Structure):
    """handtrack_gesture_state: whose (hand_id, handedness, present), then strength, active and
    event (0 none, 1 start, 2 end) per gesture."""
    _fields_ = [("hand_id", ctypes.c_uint32), ("handedness", ctypes.c_int32), ("present", ctypes.c_int32),
                ("strength", ctypes.c_float * NUM_GESTURES), ("active", ctypes.c_int32 * NUM_GESTURES),
                ("event", ctypes.c_int32 * NUM_GESTURES)]


_lib.handtrack_gestures_new.argtypes = [ctypes.POINTER(ctypes.c_void_p)]
_lib.handtrack_gestures_free.argtypes = [ctypes.c_void_p]
_lib.handtrack_gestures_free.restype = None
_lib.handtrack_gestures_reset.argtypes = [ctypes.c_void_p]
_lib.handtrack_gestures_reset.restype = None
_lib.handtrack_gestures_update.argtypes = [ctypes.c_void_p, ctypes.POINTER(Frame), ctypes.POINTER(GestureState)]
_lib.handtrack_gestures_update.restype = ctypes.c_int

if _lib.handtrack_abi_version() != ABI_VERSION:
    raise ImportError(f"handtrack: library ABI version {_lib.handtrack_abi_version()}, "
                      f"this module reads version {ABI_VERSION}: install the matching handtrack")
for _what, _size, _mine in (("frame", _lib.handtrack_frame_size(), ctypes.sizeof(Frame)),
                            ("hand", _lib.handtrack_hand_size(), ctypes.sizeof(Hand)),
                            ("writer status", _lib.handtrack_writer_status_size(), ctypes.sizeof(WriterStatus))):
    if _size != _mine:
        raise ImportError(f"handtrack: {_what} record of the library is {_size} bytes, this module's {_mine}")


def _error(status):
    message = _lib.handtrack_strerror(status).decode()
    detail = _lib.handtrack_error_detail().decode()
    return HandtrackError(status, f"{message}: {detail}" if detail else message)


class Client:
    """A read-only connection to one shared-memory pose ring (thread roles: reentrant).

    Methods return a Frame, or None when nothing arrived in time. A dead or stopped daemon is
    reported through the `trouble` attribute (ERR_WRITER_DEAD / ERR_WRITER_STOPPED, else OK);
    the client reattaches by itself when the daemon restarts. Other errors raise HandtrackError.
    """

    def __init__(self, shm_name="handtrack"):
        handle = ctypes.c_void_p()
        status = _lib.handtrack_open(shm_name.encode(), ctypes.byref(handle))
        if status != OK:
            raise _error(status)
        self._handle = handle
        self.trouble = OK

    @classmethod
    def wait_for(cls, shm_name="handtrack", timeout=30.0):
        """A Client as soon as the daemon's segment is there (it may start after this program),
        waiting at most `timeout` seconds; other errors (permission, untrusted owner, version)
        raise at once."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                return cls(shm_name)
            except HandtrackError as e:
                if e.status not in (ERR_NOT_FOUND, ERR_NOT_READY) or time.monotonic() >= deadline:
                    raise
            time.sleep(0.05)

    def close(self):
        if getattr(self, "_handle", None):  # absent when __init__ raised
            _lib.handtrack_close(self._handle)
            self._handle = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()

    def _result(self, status, frame):
        if status == OK:
            self.trouble = OK
            return frame
        if status in (TIMEOUT, NO_RECORD):
            return None
        if status in (ERR_WRITER_DEAD, ERR_WRITER_STOPPED):
            self.trouble = status
            return None
        raise _error(status)

    def latest(self):
        """The newest frame, or None if none was published yet. Never blocks."""
        frame = Frame()
        return self._result(_lib.handtrack_latest(self._handle, ctypes.byref(frame)), frame)

    def wait_next(self, timeout=1.0):
        """The next frame in order, waiting at most `timeout` seconds."""
        frame = Frame()
        status = _lib.handtrack_wait_next(self._handle, ctypes.byref(frame), int(timeout * 1e9))
        return self._result(status, frame)

    def wait_latest(self, timeout=1.0):
        """The newest frame newer than the last one returned, waiting at most `timeout` s."""
        frame = Frame()
        status = _lib.handtrack_wait_latest(self._handle, ctypes.byref(frame), int(timeout * 1e9))
        return self._result(status, frame)

    def frames(self, timeout=None, latest=False):
        """Frames in order (the newest only with latest=True), as they come: for ever, or until
        `timeout` seconds pass without one. A daemon that dies or restarts is waited for."""
        wait = self.wait_latest if latest else self.wait_next
        quiet_since = time.monotonic()
        while True:
            frame = wait(timeout=0.25)
            if frame is not None:
                quiet_since = time.monotonic()
                yield frame
            elif timeout is not None and time.monotonic() - quiet_since >= timeout:
                return

    __iter__ = frames

    async def aframes(self, timeout=None, latest=False):
        """`frames()` for asyncio: each wait runs in a worker thread, so the event loop stays free.
        Use one client per task (a client is used by one thread at a time)."""
        loop = asyncio.get_running_loop()
        wait = self.wait_latest if latest else self.wait_next
        quiet_since = time.monotonic()
        while True:
            frame = await loop.run_in_executor(None, wait, 0.25)
            if frame is not None:
                quiet_since = time.monotonic()
                yield frame
            elif timeout is not None and time.monotonic() - quiet_since >= timeout:
                return

    @property
    def missed(self):
        """Records (frames) skipped just before the last frame returned."""
        return _lib.handtrack_missed(self._handle)

    @property
    def missed_total(self):
        return _lib.handtrack_missed_total(self._handle)

    def status(self):
        """The daemon's WriterStatus (device state, liveness, epoch, statistics)."""
        out = WriterStatus()
        status = _lib.handtrack_writer_status_get(self._handle, ctypes.byref(out))
        if status != OK:
            raise _error(status)
        return out


class _Owned:
    """Frees the C object in self._handle with `_free` when garbage-collected."""
    _free = None

    def __del__(self):
        if getattr(self, "_handle", None):
            type(self)._free(self._handle)
            self._handle = None


class PoseFilter(_Owned):
    """A One Euro filter over the hands of a stream of frames (the C library's handtrack_filter;
    docs/FILTER.md), each hand followed by its hand_id. `PoseFilter()` uses the documented
    defaults; keyword arguments override them, e.g. `PoseFilter(min_cutoff_hz=0.5)`.
    `apply(frame)` smooths every hand of a Frame in place and returns the frame."""

    def __init__(self, **params):
        p = FilterParams()
        _lib.handtrack_filter_default_params(ctypes.byref(p))
        for name, value in params.items():
            if name not in dict(FilterParams._fields_):
                raise TypeError(f"PoseFilter: unknown parameter {name!r}")
            setattr(p, name, float(value))
        self.params = p
        handle = ctypes.c_void_p()
        status = _lib.handtrack_filter_new(ctypes.byref(p), ctypes.byref(handle))
        if status != OK:
            raise HandtrackError(status, f"PoseFilter: invalid parameters {params}")
        self._handle = handle

    def apply(self, frame):
        _lib.handtrack_filter_apply(self._handle, ctypes.byref(frame))
        return frame

    _free = _lib.handtrack_filter_free

    def reset(self):
        _lib.handtrack_filter_reset(self._handle)


class Gestures(_Owned):
    """Gestures of every hand of a stream of frames (the C library's handtrack_gestures;
    docs/GESTURES.md), each hand followed by its hand_id.

    `update(frame)` returns one dict per hand: the frame's hands in its order, then the hands
    that left in this frame (their gestures end there):
    {"hand_id": 3, "handedness": "right", "present": True,
     "gestures": {name: {"strength": 0..1, "active": bool, "event": None | "start" | "end"}}}."""

    _EVENTS = {0: None, 1: "start", 2: "end"}

    def __init__(self):
        handle = ctypes.c_void_p()
        status = _lib.handtrack_gestures_new(ctypes.byref(handle))
        if status != OK:
            raise _error(status)
        self._handle = handle
        self._states = (GestureState * GESTURE_MAX_STATES)()

    def update(self, frame):
        n = _lib.handtrack_gestures_update(self._handle, ctypes.byref(frame), self._states)
        if n < 0:
            raise _error(n)
        return [{"hand_id": s.hand_id, "handedness": Hand.HANDEDNESS_NAMES.get(s.handedness, "unknown"),
                 "present": bool(s.present),
                 "gestures": {name: {"strength": s.strength[g], "active": bool(s.active[g]),
                                     "event": self._EVENTS.get(s.event[g])}
                              for g, name in enumerate(GESTURE_NAMES)}}
                for s in self._states[:n]]

    _free = _lib.handtrack_gestures_free

    def reset(self):
        _lib.handtrack_gestures_reset(self._handle)
