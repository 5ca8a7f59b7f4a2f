/* The schedule versions of a run as a sensor and a fusion center both keep them, with the
 * scenario's shape (docs/wire-protocol.md, "Schedule versions and switches"). Plain C, free of
 * any DDS: the Cyclone examples here and the Fast DDS sensor (tests/interop/fastdds_sensor.cpp)
 * fill it from their own vendor's samples. */
#ifndef SENSORNET_EXAMPLES_SCHEDULE_BOOK_H
#define SENSORNET_EXAMPLES_SCHEDULE_BOOK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define RUN_MAX_VERSIONS 32

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
  uint64_t seed;   /* the run seed */
  int has_network; /* the scenario's YAML has a top-level network: section */
  int timetable;   /* arrivals are the timetable's, not Poisson (Scenario.arrivals) */
  char* yaml;      /* the scenario file's text (Scenario.yaml), for the world library */
  struct run_version versions[RUN_MAX_VERSIONS];
  int version_count;
};

/* Records the scenario (from a Scenario sample): its shape, the run seed, its YAML text and the
 * arrival mode in force ("poisson", "timetable", empty: poisson). */
void run_book_set_scenario(struct run_book* book, double horizon_s, uint32_t intervals,
                           uint32_t sensors, uint32_t state_dim, uint64_t seed, const char* yaml,
                           const char* arrivals);
/* Frees what the versions hold (their rates) and the YAML; the book is empty afterwards. */
void run_book_free(struct run_book* book);

/* Adds a version (from a Schedule sample); refused (0) when the book is full or the rates are
 * not intervals x sensors. */
int run_book_add_version(struct run_book* book, uint32_t number, uint32_t effective_episode,
                         double effective_time_s, double bracket_lower, double bracket_upper,
                         uint32_t intervals, uint32_t sensors, const double* rates, size_t count);

/* The version in force at emulated time t of `episode`: the newest that took effect by then. */
const struct run_version* run_book_in_force(const struct run_book* book, uint32_t episode,
                                            double t);
/* Sensor j's rate at t of `episode` under the version in force (0 before any). */
double run_book_rate(const struct run_book* book, uint32_t episode, double t, uint32_t j);
/* Where the rate of `episode` may change next after t: the next interval edge, or earlier where
 * a version takes effect; at most T. */
double run_book_next_change(const struct run_book* book, uint32_t episode, double t);
/* The next arrival after t of sensor j's Poisson process at the piecewise-constant rate in
 * force, from uniforms in (0, 1) that uniform(state) draws; INFINITY when none comes by T. */
double run_book_next_arrival(const struct run_book* book, uint32_t episode, double t, uint32_t j,
                             double (*uniform)(void*), void* state);

/* Sensor j's arrivals in `episode` exactly as sensornet's own agents draw them
 * (src/emulator/sensor_timeline.cpp, core/poisson_arrivals.cpp, core/random.cpp): per stretch of
 * one version, a xoshiro256++ stream keyed by (run seed, "em-arriv", episode, sensor, version,
 * the stretch's start), exponential gaps restarted at each rate interval, each instant moved to
 * the plant's tick at or before it (2^20 ticks over T). Fills malloc'ed arrays of the instants
 * and of the version each came from, in time order; returns how many (the caller frees both). */
size_t run_book_draw_as_ours(const struct run_book* book, uint32_t episode, uint32_t j,
                             double** times, uint32_t** versions);

#ifdef __cplusplus
}
#endif

#endif
