#pragma once
// How `fusion_center serve` starts: its core's configuration takes the episode log beside the
// report and, when the process was restarted (--resume), what that log and the fault log beside
// it hold, so that the report keeps every episode and fault of the process's earlier lives.
//
//   FusionCenterConfig config;
//   useLogsBeside(config, "run/report.json", /*resume=*/true);   // reads run/report.jsonl, ...

#include <string>

#include "sensornet/emulator/fusion_center_core.hpp"

namespace sensornet::emulator {

// Points `config` at the episode log beside `report_path` (report_files.hpp; none when the path
// is empty) and, with `resume`, fills resumed_log and resumed_faults from that log and the
// fault log beside it (resumed_log empty, never absent, when there is nothing to resume from).
void useLogsBeside(FusionCenterConfig& config, const std::string& report_path, bool resume);

}  // namespace sensornet::emulator
