#include "sensornet/emulator/fusion_metrics.hpp"

#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include "sensornet/io/metrics_server.hpp"

namespace sensornet::emulator {

std::string fusionCenterMetrics(const FusionCenterCore& core, const ScheduleBook& book) {
  PrometheusText out;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.gauge("sensornet_up", "1 while the fusion center serves the run", {}, 1.0);
  if (core.hasReport()) {
    const RunReport& report = core.report();
    const RunSummary s = report.summary();
    const auto& totals = report.sensorTotals();
    struct Count {
      const char* name;
      const char* help;
      std::uint64_t RunReport::SensorTotals::*field;
    };
    for (const Count& c :
         {Count{"sensornet_measurements_sent_total", "Measurements the sensor says it sent",
                &RunReport::SensorTotals::sent},
          Count{"sensornet_measurements_received_total", "Measurements fused",
                &RunReport::SensorTotals::received},
          Count{"sensornet_measurements_lost_total", "Measurements sent that never arrived",
                &RunReport::SensorTotals::lost},
          Count{"sensornet_measurements_dropped_by_network_total",
                "Measurements the emulated network dropped", &RunReport::SensorTotals::dropped_by_network},
          Count{"sensornet_measurements_late_total",
                "Measurements that arrived after fusion had passed their time",
                &RunReport::SensorTotals::late}}) {
      for (std::size_t j = 0; j < totals.size(); ++j) {
        out.counter(c.name, c.help, {{"sensor", std::to_string(j)}},
                    static_cast<double>(totals[j].*c.field));
      }
    }
    for (const auto& [reason, count] : s.rejected) {
      out.counter("sensornet_rejected_samples_total", "Samples refused on the wire, by reason",
                  {{"reason", reason}}, static_cast<double>(count));
    }
    out.counter("sensornet_episodes_total", "Episodes reported, complete or not",
                {{"outcome", "complete"}}, s.episodes_complete);
    out.counter("sensornet_episodes_total", "Episodes reported, complete or not",
                {{"outcome", "incomplete"}}, s.episodes - s.episodes_complete);
    const bool any = s.episodes_complete > 0;
    out.gauge("sensornet_realized_cost_mean", "Mean realized cost of the complete episodes", {},
              any ? s.mean : nan);
    out.gauge("sensornet_realized_cost_ci95_low", "Lower end of the mean's 95% interval", {},
              s.episodes_complete >= 2 ? s.ci95_low : nan);
    out.gauge("sensornet_realized_cost_ci95_high", "Upper end of the mean's 95% interval", {},
              s.episodes_complete >= 2 ? s.ci95_high : nan);
    const LatencyHistogram& latencies = report.latencies();
    std::vector<double> bounds;
    std::vector<std::uint64_t> cumulative;
    for (double decade = 1e-5; decade < 20.0; decade *= 10.0) {
      for (const double step : {1.0, 2.5, 5.0}) {
        if (decade * step > 10.0) break;
        bounds.push_back(decade * step);
        cumulative.push_back(latencies.countAtMost(decade * step));
      }
    }
    out.histogram("sensornet_publish_to_fusion_latency_seconds",
                  "Wall time from a measurement's publication to its arrival at the fusion center",
                  bounds, cumulative, latencies.count(), latencies.sum());
    std::map<std::string, std::uint64_t> faults;
    for (const report::FaultRecord& f : core.faults()) ++faults[std::string(wordOf(f.kind))];
    for (const auto& [kind, count] : faults) {
      out.counter("sensornet_faults_total", "Faults the fusion center recorded, by kind",
                  {{"kind", kind}}, static_cast<double>(count));
    }
  }
  if (!book.versions().empty()) {
    const ScheduleVersion& v = book.latest();
    out.gauge("sensornet_schedule_version", "The latest schedule version", {}, v.version);
    out.gauge("sensornet_schedule_bracket_lower", "J(P_info) of the latest schedule version", {},
              v.bracket.info);
    out.gauge("sensornet_schedule_bracket_upper", "J(P_cov) of the latest schedule version", {},
              v.bracket.cov);
    for (int j = 0; j < v.schedule.sensorCount(); ++j) {
      double sum = 0.0;
      for (int k = 0; k < v.schedule.intervals(); ++k) sum += v.schedule.rate(k, j);
      out.gauge("sensornet_schedule_mean_rate_hz",
                "The sensor's rate under the latest version, averaged over the horizon",
                {{"sensor", std::to_string(j)}}, sum / v.schedule.intervals());
    }
  }
  return out.str();
}

}  // namespace sensornet::emulator
