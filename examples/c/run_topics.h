/* What both C examples share (docs/wire-protocol.md): the clock, the QoS of the run's topics as
 * include/sensornet/dds/topics.hpp chooses them, and the book of schedule versions a sensor and
 * a fusion center both keep. Plain C against Cyclone DDS's C API and the generated sensornet.h. */
#ifndef SENSORNET_EXAMPLES_RUN_TOPICS_H
#define SENSORNET_EXAMPLES_RUN_TOPICS_H

#include <dds/dds.h>
#include <stdint.h>

#include "sensornet.h"

#define RUN_MAX_VERSIONS 32

/* CLOCK_REALTIME in nanoseconds since the epoch: the *_wall_time_ns of every topic. */
int64_t run_wall_ns(void);

/* Reliable (writers block up to 100 ms), in one partition; volatile, keep last 1. */
dds_qos_t* run_qos(const char* partition);
/* Reliable, transient-local, keep last `depth`, the durability service the same: what a late
 * joiner must still get (Scenario 1, Schedule 16, EpisodeControl 8, EpisodeTally 16, ...). */
dds_qos_t* run_last_known_qos(const char* partition, int32_t depth);

int run_matched_readers(dds_entity_t writer);
int run_matched_writers(dds_entity_t reader);

struct run_version {
  uint32_t number;
  uint32_t effective_episode;
  double effective_time_s;
  double bracket_lower, bracket_upper;
  double* rates; /* N x M, row-major: rates[i * M + j] */
};

/* The scenario's shape and every schedule version of the run seen so far. */
struct run_book {
  const char* run_id;
  int have_scenario;
  double horizon_s;
  uint32_t intervals, sensors, state_dim;
  int has_network; /* the scenario's YAML has a top-level network: section */
  struct run_version versions[RUN_MAX_VERSIONS];
  int version_count;
};

/* Takes what the Scenario and Schedule readers hold for book->run_id into the book; a Scenario
 * of a sensor count other than `sensors_expected` (0: any) is a one-line error and exit 2. */
void run_book_take_scenario(struct run_book* book, dds_entity_t reader, uint32_t sensors_expected,
                            const char* program);
void run_book_take_schedules(struct run_book* book, dds_entity_t reader);

/* The version in force at emulated time t of `episode`: the newest that took effect by then. */
const struct run_version* run_book_in_force(const struct run_book* book, uint32_t episode,
                                            double t);
/* Sensor j's rate at t of `episode` under the version in force (0 before any). */
double run_book_rate(const struct run_book* book, uint32_t episode, double t, uint32_t j);
/* Where the rate of `episode` may change next after t: the next interval edge, or earlier where
 * a version takes effect; at most T. */
double run_book_next_change(const struct run_book* book, uint32_t episode, double t);

#endif
