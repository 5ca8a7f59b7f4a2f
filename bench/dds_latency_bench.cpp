// Where publish-to-fusion latency goes, with nothing but the DDS layer: writer and reader
// processes exchange sensornet Measurements over Cyclone DDS on loopback, and the reader takes
// the one-way latency (its wall clock at take minus the writer's stamp just before the write).
//
//   one-way cases, varied one at a time:
//     qos       ours (the Measurement QoS of topics.hpp: reliable, keep-all, liveliness 1 s) or
//               bare (reliable, keep-last 1, volatile, as ddsperf)
//     receive   waitset (the main thread wakes on a waitset and takes) or listener (Cyclone's
//               receive thread takes in on_data_available: one thread hop less, like ddsperf)
//     writers   1 process at the full rate, or 6 processes sharing it (as 6 sensor agents)
//   ping-pong   our layer doing what ddsperf does (the pong echoes in its listener): the round
//               trip / 2, split into the hop out (to a process idle since the last ping) and the
//               hop back (to a process that wrote microseconds ago)
//   ddsperf     ping/pong at the same rate, in each round (it prints round trip / 2)
//
// Every case runs `rounds` times, interleaved, and the table gives medians.
//
//   dds_latency_bench [rate_hz=120] [samples=600] [rounds=3]

#include <dds/dds.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sensornet/dds/listener.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "support/background_process.hpp"
#include "support/ddsperf.hpp"

namespace {

using namespace std::chrono_literals;
using sensornet::emulator::wallNowNs;
using sensornet::testing::BackgroundProcess;
namespace dds = sensornet::dds;
namespace emulator = sensornet::emulator;
namespace fs = std::filesystem;

constexpr dds_domainid_t kDomain = 218;
const char* const kEchoTopic = "sensornet/bench/MeasurementEcho";

double median(std::vector<double> values) { return emulator::quantile(std::move(values), 0.5); }

dds::Qos qosNamed(const std::string& name) {
  if (name == "bare") return dds::Qos().reliable().volatileDurability().keepLast(1);
  return dds::measurementQos();
}

// Every role's entities: the measurements, and the echoes of the ping-pong.
struct Probe {
  dds::Domain domain{dds::DomainConfig::loopback(kDomain, "latency-probe")};
  dds::Participant participant{domain};
  dds::Topic<sensornet_Measurement> measurements{participant};
  dds::Topic<sensornet_Measurement> echoes{participant, kEchoTopic};
};

// Latencies (µs) collected by a callback in another thread.
struct Samples {
  std::mutex mutex;
  std::vector<double> out_us;   // one way, or the hop out of a ping-pong
  std::vector<double> back_us;  // the hop back of a ping-pong
  std::atomic<int> count{0};
};

// Sends `samples` measurements at `rate_hz`, each stamped just before the write.
void sendAtRate(dds::Writer<sensornet_Measurement>& writer, double rate_hz, int samples) {
  const std::string run = "probe";
  const std::vector<double> z(2, 0.5);
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / rate_hz));
  auto next = std::chrono::steady_clock::now();
  for (int i = 0; i < samples; ++i) {
    next += period;
    std::this_thread::sleep_until(next);
    sensornet_Measurement m{};
    m.run_id = dds::borrowString(run);
    dds::borrowSequence(m.z, z);
    m.publish_wall_time_ns = wallNowNs();
    (void)writer.write(m);
  }
}

int publish(const std::string& qos, double rate_hz, int samples) {
  Probe probe;
  dds::Writer<sensornet_Measurement> writer(probe.participant, probe.measurements, qosNamed(qos));
  if (!writer.waitForReaders(1, 10s)) return 2;
  std::this_thread::sleep_for(500ms);
  sendAtRate(writer, rate_hz, samples);
  (void)writer.waitForAcks(2s);
  return 0;
}

// Takes what is there; `stamp` is the wall clock at the start of the take.
template <class OnSample>
void takeAll(dds::Reader<sensornet_Measurement>& reader, OnSample on_sample) {
  const std::int64_t stamp = wallNowNs();
  (void)reader.takeEach(
      64, [&](const sensornet_Measurement& m, const dds::SampleInfo&) { on_sample(m, stamp); },
      [](const sensornet_Measurement&, const dds::SampleInfo&) {});
}

// Prints the median one-way latency (µs) over `samples` measurements.
int subscribe(const std::string& qos, const std::string& receive, int samples) {
  Probe probe;
  dds::Reader<sensornet_Measurement> reader(probe.participant, probe.measurements, qosNamed(qos));
  Samples got;
  const auto record = [&](const sensornet_Measurement& m, std::int64_t stamp) {
    std::lock_guard lock(got.mutex);
    got.out_us.push_back(1e-3 * static_cast<double>(stamp - m.publish_wall_time_ns));
    ++got.count;
  };
  if (receive == "listener") {
    dds::DataAvailableListener listener(reader, [&] { takeAll(reader, record); });
    while (got.count < samples) std::this_thread::sleep_for(50ms);
  } else {
    dds::ReadCondition ready(reader);
    dds::WaitSet waitset(probe.participant);
    waitset.attach(ready, 1);
    while (got.count < samples) {
      (void)waitset.wait(10ms);
      takeAll(reader, record);
    }
  }
  std::lock_guard lock(got.mutex);
  std::printf("%.1f\n", median(got.out_us));
  return 0;
}

// Ping side: sends at `rate_hz` on the Measurement topic, receives the echo in its listener and
// prints the medians of the hop out and the hop back (µs). The pong writes its own receive
// stamp into `seq`.
int ping(const std::string& qos, double rate_hz, int samples) {
  Probe probe;
  dds::Writer<sensornet_Measurement> writer(probe.participant, probe.measurements, qosNamed(qos));
  dds::Reader<sensornet_Measurement> echoes(probe.participant, probe.echoes, qosNamed(qos));
  Samples got;
  dds::DataAvailableListener listener(echoes, [&] {
    takeAll(echoes, [&](const sensornet_Measurement& m, std::int64_t stamp) {
      const auto pong_stamp = static_cast<std::int64_t>(m.seq);
      std::lock_guard lock(got.mutex);
      got.out_us.push_back(1e-3 * static_cast<double>(pong_stamp - m.publish_wall_time_ns));
      got.back_us.push_back(1e-3 * static_cast<double>(stamp - pong_stamp));
      ++got.count;
    });
  });
  if (!writer.waitForReaders(1, 10s) || !echoes.waitForWriters(1, 10s)) return 2;
  std::this_thread::sleep_for(500ms);
  sendAtRate(writer, rate_hz, samples);
  for (int waited = 0; got.count < samples && waited < 100; ++waited) std::this_thread::sleep_for(20ms);
  std::lock_guard lock(got.mutex);
  std::printf("%.1f %.1f\n", median(got.out_us), median(got.back_us));
  return 0;
}

// Pong side: echoes every measurement from its listener, with its receive stamp in `seq`.
int pong(const std::string& qos, int samples) {
  Probe probe;
  dds::Reader<sensornet_Measurement> reader(probe.participant, probe.measurements, qosNamed(qos));
  dds::Writer<sensornet_Measurement> echo(probe.participant, probe.echoes, qosNamed(qos));
  std::atomic<int> echoed{0};
  dds::DataAvailableListener listener(reader, [&] {
    takeAll(reader, [&](const sensornet_Measurement& m, std::int64_t stamp) {
      sensornet_Measurement reply = m;  // borrows m's strings and sequences for the write
      reply.seq = static_cast<std::uint64_t>(stamp);
      (void)echo.write(reply);
      ++echoed;
    });
  });
  for (int waited = 0; echoed < samples && waited < 3000; ++waited) std::this_thread::sleep_for(20ms);
  (void)echo.waitForAcks(2s);
  return 0;
}

// One one-way case: `writers` processes share `rate_hz`.
struct Case {
  std::string qos;
  std::string receive;
  int writers = 1;
  [[nodiscard]] std::string name() const {
    return "one-way " + qos + " qos, " + receive + ", " + std::to_string(writers) + " writer" +
           (writers > 1 ? "s" : "");
  }
};

double oneWay(const fs::path& dir, const std::string& self, const Case& c, double rate_hz,
              int samples) {
  const int per_writer = samples / c.writers;
  BackgroundProcess reader({self, "sub", c.qos, c.receive, std::to_string(per_writer * c.writers)},
                           (dir / "sub.log").string());
  std::vector<std::unique_ptr<BackgroundProcess>> writers;
  for (int w = 0; w < c.writers; ++w) {
    writers.push_back(std::make_unique<BackgroundProcess>(
        std::vector<std::string>{self, "pub", c.qos, std::to_string(rate_hz / c.writers),
                                 std::to_string(per_writer)},
        (dir / ("pub" + std::to_string(w) + ".log")).string()));
  }
  for (auto& w : writers) (void)w->waitForExit(60s);
  (void)reader.waitForExit(10s);
  const double us = std::atof(reader.log().c_str());
  fs::remove(dir / "sub.log");
  for (int w = 0; w < c.writers; ++w) fs::remove(dir / ("pub" + std::to_string(w) + ".log"));
  return us;
}

// Our ping-pong: {hop out, hop back} medians (µs).
std::pair<double, double> pingPong(const fs::path& dir, const std::string& self,
                                   const std::string& qos, double rate_hz, int samples) {
  BackgroundProcess pong_process({self, "pong", qos, std::to_string(samples)},
                                 (dir / "pong.log").string());
  BackgroundProcess ping_process({self, "ping", qos, std::to_string(rate_hz), std::to_string(samples)},
                                 (dir / "ping.log").string());
  (void)ping_process.waitForExit(60s);
  (void)pong_process.waitForExit(10s);
  std::istringstream text(ping_process.log());
  double out = 0.0, back = 0.0;
  text >> out >> back;
  fs::remove(dir / "ping.log");
  fs::remove(dir / "pong.log");
  return {out, back};
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.size() == 4 && args[0] == "pub") return publish(args[1], std::stod(args[2]), std::stoi(args[3]));
  if (args.size() == 4 && args[0] == "sub") return subscribe(args[1], args[2], std::stoi(args[3]));
  if (args.size() == 4 && args[0] == "ping") return ping(args[1], std::stod(args[2]), std::stoi(args[3]));
  if (args.size() == 3 && args[0] == "pong") return pong(args[1], std::stoi(args[2]));

  const double rate_hz = args.size() > 0 ? std::stod(args[0]) : 120.0;
  const int samples = args.size() > 1 ? std::stoi(args[1]) : 600;
  const int rounds = args.size() > 2 ? std::stoi(args[2]) : 3;
  const fs::path dir = fs::temp_directory_path() / ("dds-latency-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string self = fs::canonical("/proc/self/exe").string();

  const std::vector<Case> cases = {{"bare", "waitset", 1},   {"ours", "waitset", 1},
                                   {"ours", "listener", 1}, {"ours", "waitset", 6},
                                   {"ours", "listener", 6}};
  std::vector<std::vector<double>> one_way(cases.size());
  std::vector<double> ddsperf, out, back, rtt2;
  std::printf("latency at %.0f messages/s, %d samples per case, %d rounds (µs, medians)\n", rate_hz,
              samples, rounds);
  for (int round = 0; round < rounds; ++round) {
    ddsperf.push_back(
        sensornet::bench::ddsperfHalfRoundTripUs(dir, 217, static_cast<int>(rate_hz)));
    std::printf("round %d: ddsperf round trip / 2 %.1f", round, ddsperf.back());
    const auto [o, b] = pingPong(dir, self, "ours", rate_hz, samples);
    out.push_back(o);
    back.push_back(b);
    rtt2.push_back(0.5 * (o + b));
    std::printf("; our ping-pong: out %.1f, back %.1f; one way:", o, b);
    for (std::size_t k = 0; k < cases.size(); ++k) {
      one_way[k].push_back(oneWay(dir, self, cases[k], rate_hz, samples));
      std::printf(" %.1f", one_way[k].back());
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  std::printf("| what | median (µs) | / ddsperf round trip / 2 |\n|---|---|---|\n");
  const double base = median(ddsperf);
  std::printf("| ddsperf ping/pong, round trip / 2 | %.1f | 1 |\n", base);
  std::printf("| our ping-pong, round trip / 2 | %.1f | %.2f |\n", median(rtt2), median(rtt2) / base);
  std::printf("| our ping-pong, hop out (to an idle process) | %.1f | %.2f |\n", median(out),
              median(out) / base);
  std::printf("| our ping-pong, hop back (to a process that just wrote) | %.1f | %.2f |\n",
              median(back), median(back) / base);
  for (std::size_t k = 0; k < cases.size(); ++k) {
    std::printf("| %s | %.1f | %.2f |\n", cases[k].name().c_str(), median(one_way[k]),
                median(one_way[k]) / base);
  }
  fs::remove_all(dir);
  return 0;
}
