/* The emulated world of a sensornet run, for outside code (a sensor driver, a gateway, a fault
 * model, a filter under test): the plant's true state at any emulated instant of any episode, the
 * measurement noise and measurements our sensor agents draw, and the arrival instants they would
 * draw from the run's schedule versions, all bit for bit what our agents compute from the same
 * run (docs/wire-protocol.md, "The emulated world"). A stable C ABI: link with
 * `pkg-config --libs sensornet-world`; sn_world_abi_version() says which one a library has.
 *
 *   sn_world* w = sn_world_open(scenario.yaml, scenario.seed, error, sizeof error);
 *   sn_world_set_arrivals(w, scenario.arrivals);               // "poisson" (or "") / "timetable"
 *   sn_world_add_schedule(w, v.version, v.effective_episode, v.effective_time_s,
 *                         v.rates, v.intervals);                // every Schedule sample
 *   long n = sn_world_arrivals(w, episode, sensor, times, versions, capacity);
 *   for (i < n) sn_world_measure(w, episode, sensor, seq = i, times[i], z);   // what ours send
 *   sn_world_state(w, episode, t, x);                           // the truth at any t in [0, T]
 *   sn_world_close(w);
 *
 * A world is used by one thread at a time (it keeps the last descent of the plant's bridge to
 * make nearby instants cheap); open one per thread. Functions returning int give 0 on success
 * and -1 on bad input, with the reason in sn_world_error(w).
 */
#ifndef SENSORNET_WORLD_H
#define SENSORNET_WORLD_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define SN_WORLD_ABI_VERSION 1

typedef struct sn_world sn_world;

/* The ABI version of the library linked (SN_WORLD_ABI_VERSION of its header). */
int sn_world_abi_version(void);

/* The world of a run from its Scenario sample: the scenario file's text (`yaml`) and the run
 * seed. NULL when the text is not a valid scenario, the reason in `error` (a one-line message,
 * truncated to error_size; error may be NULL). */
sn_world* sn_world_open(const char* scenario_yaml, uint64_t seed, char* error, size_t error_size);
void sn_world_close(sn_world* world);

/* Why the last call on `world` failed ("" when it did not). */
const char* sn_world_error(const sn_world* world);

uint32_t sn_world_states(const sn_world* world);            /* n */
uint32_t sn_world_sensors(const sn_world* world);           /* M */
double sn_world_horizon(const sn_world* world);             /* T, seconds */
/* p_j, the size of sensor j's measurement; 0 when there is no sensor j. */
uint32_t sn_world_measurement_dim(const sn_world* world, uint32_t sensor);
/* The plant is sampled on a grid of ticks (2^20 over [0, T]): an instant t stands for the last
 * tick at or before it, which this gives (t clamped to [0, T]). */
double sn_world_on_tick(const sn_world* world, double t);

/* x(t) of `episode`: the plant's true state at the tick of t (0 <= t <= T), n values. */
int sn_world_state(sn_world* world, uint32_t episode, double t, double* x);
/* v, the measurement noise our agents draw for sensor j's seq-th measurement of `episode`
 * (N(0, R_j), keyed by run seed, episode, sensor and seq), p_j values. */
int sn_world_noise(sn_world* world, uint32_t episode, uint32_t sensor, uint64_t seq, double* v);
/* z = H_j x(t) + v: sensor j's seq-th measurement of `episode` at t, as our agents send it
 * (seq counts the sensor's arrivals in the episode from 0), p_j values. */
int sn_world_measure(sn_world* world, uint32_t episode, uint32_t sensor, uint64_t seq, double t,
                     double* z);

/* "poisson" (also "" or NULL) or "timetable": the Scenario sample's `arrivals`. */
int sn_world_set_arrivals(sn_world* world, const char* mode);
/* A schedule version, as the Schedule sample carries it: `rates` row-major, `intervals` rows of
 * M rates in Hz (`intervals` must be the scenario's N). Versions must come in increasing order
 * (a repeat of the last is ignored). */
int sn_world_add_schedule(sn_world* world, uint32_t version, uint32_t effective_episode,
                          double effective_time_s, const double* rates, uint32_t intervals);
/* The instants (on ticks, increasing) at which our agent would transmit for `sensor` in
 * `episode` under the versions added, and the version that drew each (`versions` may be NULL).
 * Returns how many there are, writing at most `capacity` (call again with more room when the
 * count exceeds it), or -1 on bad input. */
long sn_world_arrivals(sn_world* world, uint32_t episode, uint32_t sensor, double* times,
                       uint32_t* versions, size_t capacity);

#ifdef __cplusplus
}
#endif

#endif /* SENSORNET_WORLD_H */
