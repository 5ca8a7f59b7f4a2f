/* An external fusion center in C, against Cyclone DDS's C API and sensornet's IDL
 * (docs/wire-protocol.md, "Fusion center"): it takes the fusion center's role in a launched run
 * started with `--external-fusion-center`, and paces it with its Reports.
 *
 *   sensornet launch examples/c/scalar.yaml --run-id mine --domain-id 7 \
 *     --external-fusion-center --reference-fusion --require 'fusion-agreement<=1e-9'
 *   CYCLONEDDS_URI=file://$PWD/config/cyclonedds-loopback.xml \
 *     external_fusion_center --run-id mine --domain-id 7 \
 *       --a -0.3 --q 0.5 --p0 4 --w 1 --wt 2 --h 1,2,0.5 --r 1,3,0.2
 *
 * The estimator is the user's part; here it is the continuous-discrete Kalman filter of a
 * scalar plant dx = a x dt + dw (E dw^2 = q dt) watched by M sensors z_j = h_j x + v_j
 * (E v_j^2 = r_j), written out in closed form, with no code of sensornet's: between arrivals
 * P(s) = P + (2aP + q)(e^{2as} - 1)/(2a), its integral exactly; at an arrival of sensor j,
 * P <- P r_j / (r_j + h_j^2 P). The realized cost of an episode is w ∫_0^T P dt + w_T P(T)
 * (paper 1, eq. 6). The model comes from the command line (this example parses no YAML); it
 * checks that the run's Scenario is scalar and has as many sensors. The cost depends on the
 * arrival instants only, so the example keeps no mean and reports no NEES (NaN).
 *
 * What it does on the wire: reads Scenario, Schedule and EpisodeControl in the run's partition
 * sensornet/<run id>, and Measurement and EpisodeTally in every sensor partition
 * sensornet/<run id>/sensors/<ids> (its readers join the wildcard); keeps, per episode, every
 * arrival and each sensor's tally; closes an episode once every sensor in service has its tally in
 * and sent = received (a sensor the coordinator announced dead needs neither: the episode is then
 * incomplete); and writes its Report in sensornet/<run id>: the cost, the bracket of the version in
 * force, the versions the episode ran under, per-sensor counts with the expected count ∫ λ_j dt,
 * publish-to-fusion latency, a running summary. It holds a FusionState writer, as the role
 * requires, but publishes no state: a re-plan then starts from the next episode. It leaves on
 * RUN_SHUTDOWN. Not handled, and refused where it can be seen: a scenario with a `network:` section
 * (delays, drops, copies), a sensor that falls silent without dying (it would wait for its tally
 * for ever; ours gives up after a stall limit).
 */
#include <dds/dds.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "run_topics.h"
#include "sensornet.h"

#define MAX_SENSORS 64
#define MAX_OPEN 8

struct arrival {
  double t;
  uint32_t sensor;
  uint64_t seq;
};

struct sensor_count {
  uint64_t received, sent;
  int tallied;
  int failed;       /* dead before or during the episode */
  double failed_at; /* emulated time it was learned (-1: dead before the episode) */
};

struct episode {
  int open;
  uint32_t number;
  struct arrival* arrivals;
  size_t arrival_count, arrival_capacity;
  double* latencies_s;
  struct sensor_count counts[MAX_SENSORS];
};

static struct {
  struct run_book book;
  uint32_t sensors; /* from the command line */
  double a, q, p0, w, wt;
  double h[MAX_SENSORS], r[MAX_SENSORS];
  struct episode open[MAX_OPEN];
  uint32_t dead[MAX_SENSORS]; /* 1: dead since an earlier episode */
  unsigned char* closed;      /* closed[k]: episode k is reported */
  size_t closed_size;
  int shutdown;
  /* the running summary */
  uint32_t reported, complete;
  double cost_sum, cost_square_sum, lower_sum, upper_sum;
  uint64_t received_total, sent_total, lost_total;
} s;

/* --- the estimator: the scalar CD-KF in closed form ------------------------------------- */

/* (e^x - 1 - x) / x^2, without cancellation near 0. */
static double phi2(double x) {
  if (fabs(x) < 1e-2) return 0.5 + x * (1.0 / 6 + x * (1.0 / 24 + x * (1.0 / 120 + x / 720)));
  return (expm1(x) - x) / (x * x);
}

/* Propagates P over tau and returns ∫_0^tau P(s) ds. */
static double propagate(double* p, double tau) {
  if (tau <= 0.0) return 0.0;
  const double x = 2.0 * s.a * tau;
  const double drift = 2.0 * s.a * *p + s.q; /* dP/ds at s = 0 */
  const double g1 = x == 0.0 ? tau : tau * expm1(x) / x;
  const double integral = *p * tau + drift * tau * tau * phi2(x);
  *p += drift * g1;
  return integral;
}

static int by_instant(const void* left, const void* right) {
  const struct arrival *x = left, *y = right;
  if (x->t != y->t) return x->t < y->t ? -1 : 1;
  if (x->sensor != y->sensor) return x->sensor < y->sensor ? -1 : 1;
  return x->seq < y->seq ? -1 : x->seq > y->seq;
}

static double realized_cost(struct episode* e) {
  qsort(e->arrivals, e->arrival_count, sizeof *e->arrivals, by_instant);
  double p = s.p0, t = 0.0, running = 0.0;
  for (size_t i = 0; i < e->arrival_count; ++i) {
    const struct arrival* m = &e->arrivals[i];
    running += propagate(&p, m->t - t);
    t = m->t;
    const double h = s.h[m->sensor], r = s.r[m->sensor];
    p = p * r / (r + h * h * p);
  }
  running += propagate(&p, s.book.horizon_s - t);
  return s.w * running + s.wt * p;
}

/* --- episodes ---------------------------------------------------------------------------- */

static int is_closed(uint32_t k) { return k < s.closed_size && s.closed[k]; }

static void mark_closed(uint32_t k) {
  if (k >= s.closed_size) {
    const size_t size = 2 * (size_t)k + 16;
    s.closed = realloc(s.closed, size);
    memset(s.closed + s.closed_size, 0, size - s.closed_size);
    s.closed_size = size;
  }
  s.closed[k] = 1;
}

/* The open episode k, opened on first sight (a measurement may come before its start); NULL for
 * one already reported, or when MAX_OPEN are open (the coordinator keeps at most two). */
static struct episode* episode_of(uint32_t k) {
  if (is_closed(k)) return NULL;
  struct episode* free_slot = NULL;
  for (int i = 0; i < MAX_OPEN; ++i) {
    if (s.open[i].open && s.open[i].number == k) return &s.open[i];
    if (!s.open[i].open && free_slot == NULL) free_slot = &s.open[i];
  }
  if (free_slot == NULL) return NULL;
  memset(free_slot, 0, sizeof *free_slot);
  free_slot->open = 1;
  free_slot->number = k;
  for (uint32_t j = 0; j < s.sensors; ++j) {
    if (s.dead[j]) {
      free_slot->counts[j].failed = 1;
      free_slot->counts[j].failed_at = -1.0;
    }
  }
  return free_slot;
}

static int settled(const struct episode* e) {
  if (!s.book.have_scenario || s.book.version_count == 0) return 0;
  for (uint32_t j = 0; j < s.sensors; ++j) {
    const struct sensor_count* c = &e->counts[j];
    if (c->failed) continue;
    if (!c->tallied || c->received < c->sent) return 0;
  }
  return 1;
}

static double expected_count(uint32_t k, uint32_t j) {
  double t = 0.0, sum = 0.0;
  while (t < s.book.horizon_s) {
    const double end = run_book_next_change(&s.book, k, t);
    sum += run_book_rate(&s.book, k, t, j) * (end - t);
    t = end;
  }
  return sum;
}

static int by_value(const void* left, const void* right) {
  const double x = *(const double*)left, y = *(const double*)right;
  return (x > y) - (x < y);
}

/* The value below which a fraction q of the sorted values lie (nearest rank); 0 for none. */
static double quantile(const double* sorted, size_t n, double q) {
  if (n == 0) return 0.0;
  size_t i = (size_t)ceil(q * (double)n);
  return sorted[i == 0 ? 0 : i - 1];
}

static void report(dds_entity_t writer, struct episode* e) {
  const uint32_t k = e->number;
  sensornet_SensorCounts counts[MAX_SENSORS];
  uint32_t versions[RUN_MAX_VERSIONS];
  uint32_t version_count = 0;
  char reason[256] = "";
  int complete = 1;
  memset(counts, 0, sizeof counts);
  for (uint32_t j = 0; j < s.sensors; ++j) {
    const struct sensor_count* c = &e->counts[j];
    counts[j].sensor_id = j;
    counts[j].received = c->received;
    counts[j].sent = c->tallied ? c->sent : c->received;
    counts[j].lost = counts[j].sent - c->received;
    counts[j].expected = expected_count(k, j);
    if (c->failed && c->failed_at >= 0.0 && complete) {
      complete = 0;
      snprintf(reason, sizeof reason, "sensor %u failed at %.3f s", j, c->failed_at);
    }
    s.received_total += counts[j].received;
    s.sent_total += counts[j].sent;
    s.lost_total += counts[j].lost;
  }
  /* The versions the episode ran under, in the order they took over. */
  for (double t = 0.0; t < s.book.horizon_s; t = run_book_next_change(&s.book, k, t)) {
    const struct run_version* v = run_book_in_force(&s.book, k, t);
    if (v != NULL && (version_count == 0 || versions[version_count - 1] != v->number)) {
      versions[version_count++] = v->number;
    }
  }
  /* The bracket of the version in force at the end: exact when one version ran the episode. */
  const struct run_version* last = run_book_in_force(&s.book, k, s.book.horizon_s);
  const double cost = realized_cost(e);
  qsort(e->latencies_s, e->arrival_count, sizeof(double), by_value);

  ++s.reported;
  if (complete) {
    ++s.complete;
    s.cost_sum += cost;
    s.cost_square_sum += cost * cost;
    s.lower_sum += last->bracket_lower;
    s.upper_sum += last->bracket_upper;
  }
  const double n = s.complete > 0 ? (double)s.complete : NAN;
  const double mean = s.cost_sum / n;

  sensornet_Report out;
  memset(&out, 0, sizeof out);
  out.run_id = (char*)s.book.run_id;
  out.episode = k;
  out.realized_cost = cost;
  out.realtime_cost = cost; /* without a network: section, what arrived is what was measured */
  out.bracket_lower = out.delivered_bracket_lower = last->bracket_lower;
  out.bracket_upper = out.delivered_bracket_upper = last->bracket_upper;
  out.schedule_versions._buffer = versions;
  out.schedule_versions._length = out.schedule_versions._maximum = version_count;
  out.nees = NAN;
  out.counts._buffer = counts;
  out.counts._length = out.counts._maximum = s.sensors;
  out.latency_median_s = quantile(e->latencies_s, e->arrival_count, 0.5);
  out.latency_p99_s = quantile(e->latencies_s, e->arrival_count, 0.99);
  out.complete = complete;
  out.incomplete_reason = reason;
  out.summary.episodes = s.reported;
  out.summary.episodes_complete = s.complete;
  out.summary.realized_mean = mean;
  /* A normal interval, not Student's: this example's summary is for watching, the launcher
   * computes the run's own from the Reports. */
  const double sd = sqrt(fmax(0.0, (s.cost_square_sum - n * mean * mean) / (n - 1.0)));
  out.summary.realized_ci95_low = mean - 1.96 * sd / sqrt(n);
  out.summary.realized_ci95_high = mean + 1.96 * sd / sqrt(n);
  out.summary.bracket_lower_mean = out.summary.delivered_lower_mean = s.lower_sum / n;
  out.summary.bracket_upper_mean = out.summary.delivered_upper_mean = s.upper_sum / n;
  out.summary.realtime_mean = mean;
  out.summary.nees_mean = NAN;
  out.summary.received = s.received_total;
  out.summary.sent = s.sent_total;
  out.summary.lost = s.lost_total;
  out.summary.latency_median_s = out.latency_median_s;
  out.summary.latency_p99_s = out.latency_p99_s;
  while (dds_write(writer, &out) == DDS_RETCODE_TIMEOUT) {
  } /* keep-all: wait for the readers, a Report is never dropped */
  printf("external_fusion_center: episode %u realized cost %.17g%s%s\n", k, cost,
         complete ? "" : ", incomplete: ", reason);
  fflush(stdout);

  free(e->arrivals);
  free(e->latencies_s);
  e->open = 0;
  mark_closed(k);
}

/* --- the wire ---------------------------------------------------------------------------- */

static void take_measurements(dds_entity_t reader) {
  void* samples[64] = {NULL};
  dds_sample_info_t infos[64];
  int n;
  while ((n = dds_take(reader, samples, infos, 64, 64)) > 0) {
    const int64_t now = run_wall_ns();
    for (int i = 0; i < n; ++i) {
      const sensornet_Measurement* m = samples[i];
      /* Key-only samples (a writer went away) carry no measurement. */
      if (!infos[i].valid_data || strcmp(m->run_id, s.book.run_id) != 0) continue;
      if (m->sensor_id >= s.sensors) continue;
      struct episode* e = episode_of(m->episode);
      if (e == NULL) continue;
      if (e->arrival_count == e->arrival_capacity) {
        e->arrival_capacity = 2 * e->arrival_capacity + 64;
        e->arrivals = realloc(e->arrivals, e->arrival_capacity * sizeof *e->arrivals);
        e->latencies_s = realloc(e->latencies_s, e->arrival_capacity * sizeof(double));
      }
      e->arrivals[e->arrival_count] = (struct arrival){m->emulated_time_s, m->sensor_id, m->seq};
      e->latencies_s[e->arrival_count] = 1e-9 * (double)(now - m->publish_wall_time_ns);
      ++e->arrival_count;
      ++e->counts[m->sensor_id].received;
    }
    dds_return_loan(reader, samples, n);
  }
}

static void take_tallies(dds_entity_t reader) {
  void* samples[16] = {NULL};
  dds_sample_info_t infos[16];
  int n;
  while ((n = dds_take(reader, samples, infos, 16, 16)) > 0) {
    for (int i = 0; i < n; ++i) {
      const sensornet_EpisodeTally* t = samples[i];
      if (!infos[i].valid_data || strcmp(t->run_id, s.book.run_id) != 0) continue;
      if (t->sensor_id >= s.sensors) continue;
      struct episode* e = episode_of(t->episode);
      if (e == NULL) continue;
      e->counts[t->sensor_id].tallied = 1;
      e->counts[t->sensor_id].sent = t->sent;
    }
    dds_return_loan(reader, samples, n);
  }
}

static void take_controls(dds_entity_t reader) {
  void* samples[8] = {NULL};
  dds_sample_info_t infos[8];
  const int n = dds_take(reader, samples, infos, 8, 8);
  for (int i = 0; i < n; ++i) {
    const sensornet_EpisodeControl* c = samples[i];
    if (!infos[i].valid_data || strcmp(c->run_id, s.book.run_id) != 0) continue;
    if (c->command == sensornet_RUN_SHUTDOWN) s.shutdown = 1;
    if (c->command == sensornet_EPISODE_START) {
      struct episode* e = episode_of(c->episode);
      for (uint32_t k = 0; k < c->failed_sensors._length; ++k) {
        const uint32_t j = c->failed_sensors._buffer[k];
        if (j >= s.sensors) continue;
        s.dead[j] = 1;
        if (e != NULL && !e->counts[j].failed) {
          e->counts[j].failed = 1;
          e->counts[j].failed_at = -1.0; /* dead before the episode: nobody waits for it */
        }
      }
    }
    if (c->command == sensornet_EPISODE_SENSORS_FAILED) {
      for (uint32_t k = 0; k < c->failed_sensors._length; ++k) {
        const uint32_t j = c->failed_sensors._buffer[k];
        if (j >= s.sensors) continue;
        /* Dead from failed_at_s of this episode: nobody waits for it here or later. An earlier
         * episode still open waited for its tally, which will not come: it ended there. */
        for (int o = 0; o < MAX_OPEN; ++o) {
          struct sensor_count* count = &s.open[o].counts[j];
          const uint32_t episode = s.open[o].number;
          if (!s.open[o].open || count->failed) continue;
          count->failed = 1;
          count->failed_at = episode == c->episode  ? c->failed_at_s
                             : episode < c->episode ? s.book.horizon_s
                                                    : -1.0;
        }
        s.dead[j] = 1;
      }
    }
  }
  if (n > 0) dds_return_loan(reader, samples, n);
}

/* Whether a SensorStatus of every sensor of the run has come, dead ones included (it may stop
 * writing, but it spoke once). */
static int every_sensor_heard(dds_entity_t reader) {
  static int heard[MAX_SENSORS];
  void* samples[16] = {NULL};
  dds_sample_info_t infos[16];
  int n;
  while ((n = dds_take(reader, samples, infos, 16, 16)) > 0) {
    for (int i = 0; i < n; ++i) {
      const sensornet_SensorStatus* st = samples[i];
      if (infos[i].valid_data && strcmp(st->run_id, s.book.run_id) == 0 &&
          st->sensor_id < s.sensors) {
        heard[st->sensor_id] = 1;
      }
    }
    dds_return_loan(reader, samples, n);
  }
  for (uint32_t j = 0; j < s.sensors; ++j) {
    if (!heard[j]) return 0;
  }
  return 1;
}

/* "1,2,0.5" into values; returns how many, or -1 past `capacity` or on a bad number. */
static int parse_list(const char* text, double* values, int capacity) {
  int count = 0;
  const char* p = text;
  while (*p != '\0') {
    char* end = NULL;
    const double v = strtod(p, &end);
    if (end == p || count == capacity) return -1;
    values[count++] = v;
    p = *end == ',' ? end + 1 : end;
    if (*end != ',' && *end != '\0') return -1;
  }
  return count;
}

static void usage(const char* why) {
  if (why != NULL) fprintf(stderr, "external_fusion_center: %s\n", why);
  fprintf(stderr,
          "usage: external_fusion_center --run-id ID [--domain-id D] --a A --q Q --p0 P0 "
          "--w W --wt WT --h H0,H1,... --r R0,R1,...\n");
  exit(2);
}

static double number(const char* option, const char* text) {
  char* end = NULL;
  const double v = strtod(text, &end);
  if (end == text || *end != '\0') {
    fprintf(stderr, "external_fusion_center: %s: expected a number, got '%s'\n", option, text);
    exit(2);
  }
  return v;
}

int main(int argc, char** argv) {
  dds_domainid_t domain = DDS_DOMAIN_DEFAULT;
  int h_count = -1, r_count = -1;
  s.p0 = NAN;
  s.q = NAN;
  s.a = NAN;
  s.w = 0.0;
  s.wt = 0.0;
  for (int i = 1; i < argc; i += 2) {
    if (i + 1 == argc) usage("every option takes a value");
    const char *o = argv[i], *v = argv[i + 1];
    if (strcmp(o, "--run-id") == 0)
      s.book.run_id = v;
    else if (strcmp(o, "--domain-id") == 0)
      domain = (dds_domainid_t)number(o, v);
    else if (strcmp(o, "--a") == 0)
      s.a = number(o, v);
    else if (strcmp(o, "--q") == 0)
      s.q = number(o, v);
    else if (strcmp(o, "--p0") == 0)
      s.p0 = number(o, v);
    else if (strcmp(o, "--w") == 0)
      s.w = number(o, v);
    else if (strcmp(o, "--wt") == 0)
      s.wt = number(o, v);
    else if (strcmp(o, "--h") == 0)
      h_count = parse_list(v, s.h, MAX_SENSORS);
    else if (strcmp(o, "--r") == 0)
      r_count = parse_list(v, s.r, MAX_SENSORS);
    else
      usage("unknown option");
  }
  if (s.book.run_id == NULL) usage("--run-id is required");
  if (isnan(s.a) || isnan(s.q) || isnan(s.p0)) usage("--a, --q and --p0 are required");
  if (h_count <= 0 || h_count != r_count)
    usage("--h and --r: one value per sensor, as many of each");
  for (int j = 0; j < r_count; ++j) {
    if (!(s.r[j] > 0.0)) usage("--r: every noise variance must be positive");
  }
  s.sensors = (uint32_t)h_count;

  char run[256], sensors[300];
  snprintf(run, sizeof run, "sensornet/%s", s.book.run_id);
  snprintf(sensors, sizeof sensors, "sensornet/%s/sensors/*", s.book.run_id);
  const dds_entity_t participant = dds_create_participant(domain, NULL, NULL);
  if (participant < 0) {
    fprintf(stderr, "external_fusion_center: cannot join DDS domain: %s\n",
            dds_strretcode(participant));
    return 1;
  }
  const dds_entity_t t_scenario =
      dds_create_topic(participant, &sensornet_Scenario_desc, "sensornet/Scenario", NULL, NULL);
  const dds_entity_t t_schedule =
      dds_create_topic(participant, &sensornet_Schedule_desc, "sensornet/Schedule", NULL, NULL);
  const dds_entity_t t_control = dds_create_topic(participant, &sensornet_EpisodeControl_desc,
                                                  "sensornet/EpisodeControl", NULL, NULL);
  const dds_entity_t t_measurement = dds_create_topic(participant, &sensornet_Measurement_desc,
                                                      "sensornet/Measurement", NULL, NULL);
  const dds_entity_t t_tally = dds_create_topic(participant, &sensornet_EpisodeTally_desc,
                                                "sensornet/EpisodeTally", NULL, NULL);
  const dds_entity_t t_report =
      dds_create_topic(participant, &sensornet_Report_desc, "sensornet/Report", NULL, NULL);
  const dds_entity_t t_state = dds_create_topic(participant, &sensornet_FusionState_desc,
                                                "sensornet/FusionState", NULL, NULL);
  const dds_entity_t t_status = dds_create_topic(participant, &sensornet_SensorStatus_desc,
                                                 "sensornet/SensorStatus", NULL, NULL);

  dds_qos_t* q = run_last_known_qos(run, 1);
  const dds_entity_t scenarios = dds_create_reader(participant, t_scenario, q, NULL);
  dds_delete_qos(q);
  q = run_last_known_qos(run, 16);
  const dds_entity_t schedules = dds_create_reader(participant, t_schedule, q, NULL);
  dds_delete_qos(q);
  q = run_last_known_qos(run, 8);
  const dds_entity_t controls = dds_create_reader(participant, t_control, q, NULL);
  dds_delete_qos(q);
  q = run_qos(sensors); /* Measurement: reliable, keep-all, volatile */
  dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  const dds_entity_t measurements = dds_create_reader(participant, t_measurement, q, NULL);
  dds_delete_qos(q);
  q = run_last_known_qos(sensors, 16);
  const dds_entity_t tallies = dds_create_reader(participant, t_tally, q, NULL);
  dds_delete_qos(q);
  /* Created after the Measurement reader: a sensor process whose status writer has matched this
   * reader has discovered the Measurement reader before it (a participant announces its readers
   * in order), so its Measurement writer is matched too. */
  q = run_last_known_qos(sensors, 1);
  const dds_entity_t statuses = dds_create_reader(participant, t_status, q, NULL);
  dds_delete_qos(q);
  if (scenarios < 0 || schedules < 0 || controls < 0 || measurements < 0 || tallies < 0 ||
      statuses < 0) {
    fprintf(stderr, "external_fusion_center: cannot create the run's readers\n");
    return 1;
  }

  /* The role's writers come last, once every sensor process is heard: the coordinator counts
   * the fusion center present when they match, and starts the first episode soon after; a
   * Measurement reader that had not matched a sensor's writer by then would miss its first
   * measurements (the topic is volatile). */
  dds_entity_t reports = 0, states = 0;
  int checked = 0;
  while (!s.shutdown) {
    run_book_take_scenario(&s.book, scenarios, s.sensors, "external_fusion_center");
    if (s.book.have_scenario && !checked) {
      if (s.book.state_dim != 1) {
        fprintf(stderr,
                "external_fusion_center: run %s has a state of dimension %u; this "
                "example's filter is scalar\n",
                s.book.run_id, s.book.state_dim);
        return 2;
      }
      if (s.book.has_network) {
        fprintf(stderr,
                "external_fusion_center: run %s emulates a network (the scenario's "
                "network: section); this example does not model delays, drops or copies\n",
                s.book.run_id);
        return 2;
      }
      checked = 1;
    }
    run_book_take_schedules(&s.book, schedules);
    take_controls(controls);
    if (reports == 0 && s.book.have_scenario && every_sensor_heard(statuses) &&
        run_matched_writers(measurements) >= run_matched_writers(statuses)) {
      q = run_last_known_qos(run, 1); /* Report: keep-all writer, last 1 for late joiners */
      dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
      dds_qset_writer_data_lifecycle(q, false);
      reports = dds_create_writer(participant, t_report, q, NULL);
      dds_delete_qos(q);
      q = run_qos(run);
      states = dds_create_writer(participant, t_state, q, NULL);
      dds_delete_qos(q);
      if (reports < 0 || states < 0) {
        fprintf(stderr,
                "external_fusion_center: cannot create the Report and FusionState writers\n");
        return 1;
      }
    }
    take_measurements(measurements);
    take_tallies(tallies);
    for (int o = 0; o < MAX_OPEN; ++o) {
      if (reports > 0 && s.open[o].open && settled(&s.open[o])) report(reports, &s.open[o]);
    }
    dds_sleepfor(DDS_MSECS(1));
  }
  if (reports > 0) (void)dds_wait_for_acks(reports, DDS_SECS(2));
  dds_delete(participant);
  run_book_free(&s.book);
  for (int o = 0; o < MAX_OPEN; ++o) { /* what the run ended with still unreported, and why */
    if (!s.open[o].open) continue;
    fprintf(stderr, "external_fusion_center: episode %u not reported:", s.open[o].number);
    for (uint32_t j = 0; j < s.sensors; ++j) {
      const struct sensor_count* c = &s.open[o].counts[j];
      if (c->failed) continue;
      if (!c->tallied)
        fprintf(stderr, " sensor %u: no tally (%llu received);", j,
                (unsigned long long)c->received);
      else if (c->received < c->sent)
        fprintf(stderr, " sensor %u: %llu of %llu received;", j, (unsigned long long)c->received,
                (unsigned long long)c->sent);
    }
    fprintf(stderr, "\n");
  }
  printf("external_fusion_center: reported %u episodes, %u complete, mean realized cost %.6g\n",
         s.reported, s.complete, s.complete > 0 ? s.cost_sum / s.complete : NAN);
  return 0;
}
