#pragma once
// The fusion center's live state as Prometheus metrics (io/metrics_server.hpp), served while a
// run lives (`fusion_center serve --metrics ADDR`, `sensornet launch --metrics ADDR`). Counters
// are over the episodes reported so far; names and units follow Prometheus' conventions
// (`_total` counters, seconds, Hz):
//
//   sensornet_measurements_{sent,received,lost,dropped_by_network,late}_total{sensor}
//   sensornet_rejected_samples_total{reason}      sensornet_episodes_total{outcome}
//   sensornet_faults_total{kind}
//   sensornet_realized_cost_mean, _ci95_low, _ci95_high   (NaN before a complete episode)
//   sensornet_schedule_version, sensornet_schedule_bracket_{lower,upper} (the latest version's)
//   sensornet_schedule_mean_rate_hz{sensor}       (the latest version's, over the horizon)
//   sensornet_publish_to_fusion_latency_seconds   (histogram, 10 us .. 10 s)

#include <string>

#include "sensornet/emulator/fusion_center_core.hpp"
#include "sensornet/emulator/schedule_book.hpp"

namespace sensornet::emulator {

[[nodiscard]] std::string fusionCenterMetrics(const FusionCenterCore& core, const ScheduleBook& book);

}  // namespace sensornet::emulator
