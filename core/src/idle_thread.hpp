#pragma once
// Threads that do a tracker's work off the frame (a check's search: background_search.hpp; a hand's
// self-calibration: self_calibration.hpp) run at the lowest scheduling priority.
#include <thread>

namespace handtrack {

// The calling thread named `name` (at most 15 characters), at SCHED_IDLE (only CPU time no other
// thread of the machine wants: a pipeline thread that wakes preempts it at once), allowed on every
// online CPU (it inherits the creating thread's policy and CPU, which in handtrackd may be a
// real-time stage thread pinned to one CPU). Either may fail in a restricted container; the thread
// then runs as its creator does.
void become_idle_class(const char* name);

// Joins `thread` after moving it back to the normal class, so that work starved of idle time
// reaches its end (or its next stop check) soon.
void join_from_idle_class(std::thread& thread);

}  // namespace handtrack
