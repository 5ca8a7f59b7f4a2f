#pragma once
// A participant of one sensornet run for Python (participant.cpp): readers and writers of every
// topic of docs/wire-protocol.md, samples as dicts.

#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

namespace sensornet::python {

// A reader or a writer of one topic in one partition of the run.
class Endpoint {
 public:
  struct Impl;
  [[nodiscard]] std::string topic() const;
  // How many writers (of a reader) or readers (of a writer) it has matched.
  [[nodiscard]] int matched() const;
  // The samples with data the reader holds, taken, as dicts (at most max_samples).
  pybind11::list take(int max_samples);
  // Writes one sample from a dict; a reliable writer's timeouts are retried (nothing dropped).
  void write(const pybind11::dict& values);
  // Waits until every matched reader acknowledged what was written; false on timeout.
  bool waitForAcks(double seconds);

 private:
  friend class Participant;
  std::shared_ptr<Impl> impl_;
};

class Participant {
 public:
  struct Impl;
  // Joins the DDS domain (-1: Cyclone's default, or CYCLONEDDS_URI's) for run `run_id`.
  Participant(const std::string& run_id, int domain_id);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  [[nodiscard]] const std::string& runId() const;
  // An endpoint of `topic` ("Measurement" or "sensornet/Measurement") with the QoS every process
  // of a run uses, in partition sensornet/<run id>[/<partition>] ("sensors/1", "sensors/*",
  // "operator").
  Endpoint endpoint(const std::string& topic, const std::string& partition, bool reader);
  // Leaves the domain: every endpoint of it stops working.
  void close();

 private:
  std::shared_ptr<Impl> impl_;
};

void bindParticipant(pybind11::module_& m);

}  // namespace sensornet::python
