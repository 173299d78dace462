"""handtrack: read hand poses published by handtrackd, from Python.

A thin ctypes binding over the stable C library (libhandtrack_client.so, handtrack/client.h):
the same read-only mapping, seqlock and futex wait as C and C++ clients. The record layout
below mirrors ``handtrack_pose``; at import the module checks the library's ABI version and
record size against it and refuses to load on a mismatch.

    import handtrack
    with handtrack.Client("handtrack") as client:
        pose = client.wait_next(timeout=1.0)        # None on timeout
        if pose is not None:
            print(pose.frame, pose.state_name, pose.fingertips_mm[1][:])

The library is found through $HANDTRACK_CLIENT_LIB, then the system's library path.

Iterating: ``for pose in client.poses(): ...`` (or ``async for pose in client.aposes()`` in
asyncio code). With NumPy installed, ``pose.joints``, ``pose.fingertips`` and ``pose.params`` are
arrays (21x3, 5x3, 26); without it, lists. Smoothing (``PoseFilter``) and gestures (``Gestures``)
come from the C library.
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

__all__ = ["Client", "Pose", "Stats", "WriterStatus", "HandtrackError", "ABI_VERSION",
           "TIMEOUT", "NO_RECORD", "ERR_WRITER_DEAD", "ERR_WRITER_STOPPED",
           "ERR_UNTRUSTED_OWNER", "PoseFilter", "FilterParams", "Gestures", "GESTURE_NAMES"]

ABI_VERSION = 1
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


class Pose(ctypes.Structure):
    """One pose; same layout as handtrack_pose (640 bytes)."""
    _fields_ = [
        ("frame", ctypes.c_uint64),
        ("epoch", ctypes.c_uint64),
        ("capture_ns", ctypes.c_int64),
        ("publish_ns", ctypes.c_int64),
        ("grab_ms", ctypes.c_float),
        ("preprocess_ms", ctypes.c_float),
        ("optimize_ms", ctypes.c_float),
        ("publish_ms", ctypes.c_float),
        ("state", ctypes.c_int32),
        ("confidence", ctypes.c_float),
        ("energy", ctypes.c_float),
        ("flags", ctypes.c_uint32),
        ("params", ctypes.c_double * NUM_PARAMS),
        ("joints_mm", _Vec3 * NUM_JOINTS),
        ("fingertips_mm", _Vec3 * NUM_FINGERTIPS),
        ("palm_center_mm", _Vec3),
        ("palm_normal", _Vec3),
        ("pinch_distance_mm", ctypes.c_float),
        ("pinch_strength", ctypes.c_float),
        ("hand_scale", ctypes.c_float * 3),
        ("reserved", ctypes.c_uint32 * 3),
    ]

    STATE_NAMES = {0: "no_hand", 1: "tracking", 2: "recovering"}

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
        """The fields handtrack-cat prints, as plain Python values."""
        return {
            "frame": self.frame, "epoch": self.epoch, "state": self.state_name,
            "capture_ns": self.capture_ns, "publish_ns": self.publish_ns,
            "confidence": self.confidence, "energy": self.energy,
            "params": list(self.params),
            "joints": [list(j) for j in self.joints_mm],
            "fingertips": [list(t) for t in self.fingertips_mm],
            "pinch": {"distance_mm": self.pinch_distance_mm, "strength": self.pinch_strength},
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
    candidates.append("libhandtrack_client.so.1")
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
_lib.handtrack_pose_size.restype = ctypes.c_size_t
_lib.handtrack_writer_status_size.restype = ctypes.c_size_t
_lib.handtrack_open.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_void_p)]
_lib.handtrack_close.argtypes = [ctypes.c_void_p]
_lib.handtrack_close.restype = None
_lib.handtrack_latest.argtypes = [ctypes.c_void_p, ctypes.POINTER(Pose)]
_lib.handtrack_wait_next.argtypes = [ctypes.c_void_p, ctypes.POINTER(Pose), ctypes.c_int64]
_lib.handtrack_wait_latest.argtypes = [ctypes.c_void_p, ctypes.POINTER(Pose), ctypes.c_int64]
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
_lib.handtrack_filter_apply.argtypes = [ctypes.c_void_p, ctypes.POINTER(Pose)]

NUM_GESTURES = 3
GESTURE_NAMES = ("pinch", "grab", "point")  # handtrack_gesture order


class GestureState(ctypes.Structure):
    """handtrack_gesture_state: strength, active and event (0 none, 1 start, 2 end) per gesture."""
    _fields_ = [("strength", ctypes.c_float * NUM_GESTURES), ("active", ctypes.c_int32 * NUM_GESTURES),
                ("event", ctypes.c_int32 * NUM_GESTURES)]


_lib.handtrack_gestures_new.argtypes = [ctypes.POINTER(ctypes.c_void_p)]
_lib.handtrack_gestures_free.argtypes = [ctypes.c_void_p]
_lib.handtrack_gestures_free.restype = None
_lib.handtrack_gestures_reset.argtypes = [ctypes.c_void_p]
_lib.handtrack_gestures_reset.restype = None
_lib.handtrack_gestures_update.argtypes = [ctypes.c_void_p, ctypes.POINTER(Pose), ctypes.POINTER(GestureState)]

if _lib.handtrack_abi_version() != ABI_VERSION:
    raise ImportError(f"handtrack: library ABI version {_lib.handtrack_abi_version()}, "
                      f"this module reads version {ABI_VERSION}")
if _lib.handtrack_pose_size() != ctypes.sizeof(Pose) or \
        _lib.handtrack_writer_status_size() != ctypes.sizeof(WriterStatus):
    raise ImportError("handtrack: record layout of the library and this module differ "
                      f"({_lib.handtrack_pose_size()} vs {ctypes.sizeof(Pose)} bytes)")


def _error(status):
    message = _lib.handtrack_strerror(status).decode()
    detail = _lib.handtrack_error_detail().decode()
    return HandtrackError(status, f"{message}: {detail}" if detail else message)


class Client:
    """A read-only connection to one shared-memory pose ring (thread roles: reentrant).

    Methods return a Pose, or None when nothing arrived in time. A dead or stopped daemon is
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
        if self._handle:
            _lib.handtrack_close(self._handle)
            self._handle = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self.close()

    def _result(self, status, pose):
        if status == OK:
            self.trouble = OK
            return pose
        if status in (TIMEOUT, NO_RECORD):
            return None
        if status in (ERR_WRITER_DEAD, ERR_WRITER_STOPPED):
            self.trouble = status
            return None
        raise _error(status)

    def latest(self):
        """The newest pose, or None if none was published yet. Never blocks."""
        pose = Pose()
        return self._result(_lib.handtrack_latest(self._handle, ctypes.byref(pose)), pose)

    def wait_next(self, timeout=1.0):
        """The next pose in order, waiting at most `timeout` seconds."""
        pose = Pose()
        status = _lib.handtrack_wait_next(self._handle, ctypes.byref(pose), int(timeout * 1e9))
        return self._result(status, pose)

    def wait_latest(self, timeout=1.0):
        """The newest pose newer than the last one returned, waiting at most `timeout` s."""
        pose = Pose()
        status = _lib.handtrack_wait_latest(self._handle, ctypes.byref(pose), int(timeout * 1e9))
        return self._result(status, pose)

    def poses(self, timeout=None, latest=False):
        """Poses in order (the newest only with latest=True), as they come: for ever, or until
        `timeout` seconds pass without one. A daemon that dies or restarts is waited for."""
        wait = self.wait_latest if latest else self.wait_next
        quiet_since = time.monotonic()
        while True:
            pose = wait(timeout=0.25)
            if pose is not None:
                quiet_since = time.monotonic()
                yield pose
            elif timeout is not None and time.monotonic() - quiet_since >= timeout:
                return

    __iter__ = poses

    async def aposes(self, timeout=None, latest=False):
        """`poses()` for asyncio: each wait runs in a worker thread, so the event loop stays free.
        Use one client per task (a client is used by one thread at a time)."""
        loop = asyncio.get_running_loop()
        wait = self.wait_latest if latest else self.wait_next
        quiet_since = time.monotonic()
        while True:
            pose = await loop.run_in_executor(None, wait, 0.25)
            if pose is not None:
                quiet_since = time.monotonic()
                yield pose
            elif timeout is not None and time.monotonic() - quiet_since >= timeout:
                return

    @property
    def missed(self):
        """Records skipped just before the last pose returned."""
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
    """A One Euro filter over poses (the C library's handtrack_filter; docs/FILTER.md), one per
    hand. `PoseFilter()` uses the documented defaults; keyword arguments override them, e.g.
    `PoseFilter(min_cutoff_hz=0.5)`. `apply(pose)` smooths a Pose in place and returns it."""

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

    def apply(self, pose):
        _lib.handtrack_filter_apply(self._handle, ctypes.byref(pose))
        return pose

    _free = _lib.handtrack_filter_free

    def reset(self):
        _lib.handtrack_filter_reset(self._handle)


class Gestures(_Owned):
    """Gestures of one hand (the C library's handtrack_gestures; docs/GESTURES.md).

    `update(pose)` returns a dict per gesture name: {"strength": 0..1, "active": bool,
    "event": None | "start" | "end"}, with the library's hysteresis."""

    _EVENTS = {0: None, 1: "start", 2: "end"}

    def __init__(self):
        handle = ctypes.c_void_p()
        status = _lib.handtrack_gestures_new(ctypes.byref(handle))
        if status != OK:
            raise _error(status)
        self._handle = handle
        self._state = GestureState()

    def update(self, pose):
        _lib.handtrack_gestures_update(self._handle, ctypes.byref(pose), ctypes.byref(self._state))
        return {name: {"strength": self._state.strength[g], "active": bool(self._state.active[g]),
                       "event": self._EVENTS.get(self._state.event[g])}
                for g, name in enumerate(GESTURE_NAMES)}

    _free = _lib.handtrack_gestures_free

    def reset(self):
        _lib.handtrack_gestures_reset(self._handle)
