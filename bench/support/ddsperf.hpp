#pragma once
// Cyclone's own `ddsperf` on loopback, as the yardstick of the emulator's benchmarks: ping/pong
// for latency, pub/sub for throughput.
//
// What ddsperf prints: for each second, the round trips of that second, each already HALVED
// (ddsperf records (t_pong_received - t_ping_written) / 2; see update_roundtrip() in its source).
// The printed "50%" is thus the median round trip / 2, not the round trip. checkHalving() shows
// it on the installed binary: pinging back to back, (printed mean) x 2 x (round trips in the
// second) fills the second, ≈ 1.

#include <filesystem>
#include <vector>

namespace sensornet::bench {

struct DdsperfSecond {
  double median_us = 0.0;  // as printed: round trip / 2
  double mean_us = 0.0;    // as printed: round trip / 2
  long round_trips = 0;
};

// Runs `ddsperf pong` and `ddsperf ping` (at `rate_hz`, or back to back if 0) for `seconds` on
// domain `domain_id` with sensornet's loopback configuration; returns the per-second statistics
// of the ping side (empty if ddsperf failed). Logs go to `dir`.
[[nodiscard]] std::vector<DdsperfSecond> runDdsperf(const std::filesystem::path& dir,
                                                     int domain_id, int rate_hz, int seconds);

// The median over seconds of ddsperf's per-second median round trip / 2 (µs).
[[nodiscard]] double ddsperfHalfRoundTripUs(const std::filesystem::path& dir, int domain_id,
                                            int rate_hz);

// Back-to-back pinging: the median over seconds of 2 x mean x round trips / 1 s. About 1 if the
// printed latencies are round trip / 2 (about 0.5 if they were whole round trips).
[[nodiscard]] double checkHalving(const std::filesystem::path& dir, int domain_id);

// What `ddsperf sub` received from one `ddsperf pub` publishing as fast as it can.
struct DdsperfThroughput {
  std::vector<double> samples_per_s;  // per whole second, the first and the last left out
  long lost = 0;                      // gaps in the sequence numbers, as ddsperf counts them
  int peers = 0;                      // participants the subscriber saw besides itself (1 if alone)
};

// Runs `ddsperf sub` and `ddsperf pub size <sample_bytes>` for `seconds` on domain `domain_id`
// with sensornet's loopback configuration, reliable and keep-all as sensornet's Measurement
// topic. Logs go to `dir`. Empty samples_per_s if ddsperf failed.
[[nodiscard]] DdsperfThroughput ddsperfThroughput(const std::filesystem::path& dir, int domain_id,
                                                  int sample_bytes, int seconds);

// `ddsperf sub` and `publishers` processes of `ddsperf pub <rate_hz_each>Hz size <sample_bytes>`,
// reliable and keep-all, publishers as leaves (participant index none, as sensor agents): the
// transport alone at a fleet's shape. Logs go to `dir`.
struct DdsperfFleet {
  double samples_per_s = 0.0;  // what the subscriber received, median over whole seconds
  long lost = 0;
  double busy_share = 0.0;     // of all cores, from /proc/stat, over the middle seconds
  int cores = 0;
};
[[nodiscard]] DdsperfFleet ddsperfFleet(const std::filesystem::path& dir, int domain_id,
                                        int publishers, double rate_hz_each, int sample_bytes,
                                        int seconds);

}  // namespace sensornet::bench
