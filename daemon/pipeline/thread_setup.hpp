#pragma once
// How a pipeline thread sets itself up: its name (as top and the journal show it), its CPU and
// its scheduling class (PipelineConfig). Failures to pin or to get SCHED_FIFO are warnings: the
// pipeline runs unpinned, at normal priority.
#include "handtrack/daemon/config.hpp"

namespace handtrack::daemon {

// Called by the thread itself, first thing. `cpu` < 0: any CPU.
void setup_pipeline_thread(const char* name, int cpu, const PipelineConfig& config);

}  // namespace handtrack::daemon
