#pragma once
// How a pipeline thread sets itself up: its name (as top and the journal show it), its CPU and
// its scheduling class (PipelineConfig). Failures to pin or to get SCHED_FIFO are warnings: the
// pipeline runs unpinned, at normal priority.
#include "handtrack/daemon/config.hpp"

namespace handtrack::daemon {

// Which stage a thread works for. A frame in a later stage is older, and the frames behind it wait
// for it anyway, so where two stage threads share a CPU the later stage's goes first: the
// preprocessing of the next frame yields to the optimisation of this one (ht-optimize-2 shares
// ht-preprocess's CPU, ht-preprocess-2 ht-optimize's).
enum class StageRank { kPreprocess, kOther };

// Called by the thread itself, first thing. `cpu` < 0: any CPU.
void setup_pipeline_thread(const char* name, int cpu, const PipelineConfig& config,
                           StageRank rank = StageRank::kOther);

}  // namespace handtrack::daemon
