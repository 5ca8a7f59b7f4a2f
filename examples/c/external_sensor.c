/* An external sensor in C, against Cyclone DDS's C API and sensornet's IDL (docs/wire-protocol.md,
 * "Sensor"): it speaks for one sensor of a launched run started with `--external-sensors J`.
 *
 *   sensornet launch scenarios/default.yaml --run-id mine --domain-id 7 --external-sensors 1
 *   CYCLONEDDS_URI=file://$PWD/config/cyclonedds-loopback.xml \
 *     external_sensor --run-id mine --domain-id 7 --sensor 1 --dim 1
 *
 * It reads the Scenario (T, N, M), the Schedule versions and EpisodeControl in the run's
 * partition sensornet/<run id>; says SENSOR_READY once it holds a scenario and a schedule and
 * its writers and control reader are matched; in each episode draws Poisson arrivals at the
 * rates of the version in force, exactly as sensornet's agents draw them from the run seed
 * (schedule_book.h, run_book_draw_as_ours: the run is then the same run as with our agent,
 * costs to the bit), or with --seed S from a stream of its own (another draw, as valid);
 * publishes a Measurement at each arrival at its wall time and
 * the EpisodeTally after T, all in partition sensornet/<run id>/sensors/<J>; and leaves on
 * RUN_SHUTDOWN. A measurement is what sensornet's agents would measure at its instant, from the
 * emulated world library (sensornet/world.h: the plant's truth and the noise keyed by the run
 * seed), so that the run's NEES and errors are those of our agents; with --measure zero it is
 * z = 0 instead, which measures nothing (the run's NEES check then fails). A driver would put its
 * reading there.
 * The QoS are those of include/sensornet/dds/topics.hpp, which a reader checks on matching.
 */
#include <dds/dds.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "run_topics.h"
#include "sensornet.h"
#include "sensornet/world.h"

#define MAX_STARTS 8
#define MAX_DIM 16

struct start {
  uint32_t episode;
  int64_t start_ns;
  double time_scale;
};

static struct {
  uint32_t sensor;
  uint32_t dim;
  struct run_book book;
  struct start starts[MAX_STARTS];
  int start_count;
  int running;
  struct start now;
  double next_t; /* own draw: emulated time of the next arrival; > T: none left */
  uint64_t seq;
  int as_ours;   /* draw the arrivals as sensornet's agents do (no --seed) */
  double* drawn; /* as ours: the running episode's instants, and their versions */
  uint32_t* drawn_versions;
  size_t drawn_count;
  int drawn_with; /* how many schedule versions the book held when they were drawn */
  int failed, shutdown;
  int zero;        /* --measure zero: z = 0 */
  sn_world* world; /* the emulated world of the run, opened from its Scenario sample */
  uint64_t sent_total;
  uint64_t rng;
} s;

/* xorshift64*: a uniform in (0, 1). */
static double uniform(void* unused) {
  (void)unused;
  s.rng ^= s.rng >> 12;
  s.rng ^= s.rng << 25;
  s.rng ^= s.rng >> 27;
  return ((double)((s.rng * 2685821657736338717ULL) >> 11) + 0.5) / 9007199254740992.0;
}

/* Draws the running episode's arrivals as ours (again when a version came: the stretches before
 * it draw the same instants, their streams are keyed by where they start). */
static void draw_as_ours(void) {
  free(s.drawn);
  free(s.drawn_versions);
  s.drawn_count =
      run_book_draw_as_ours(&s.book, s.now.episode, s.sensor, &s.drawn, &s.drawn_versions);
  s.drawn_with = s.book.version_count;
}

/* The instant of the running episode's next arrival (INFINITY: none left) and its version. */
static double next_instant(uint32_t* version) {
  if (s.as_ours) {
    if (s.seq >= s.drawn_count) return INFINITY;
    *version = s.drawn_versions[s.seq];
    return s.drawn[s.seq];
  }
  if (s.next_t <= s.book.horizon_s) {
    *version = run_book_in_force(&s.book, s.now.episode, s.next_t)->number;
  }
  return s.next_t;
}

static void publish_status(dds_entity_t writer, sensornet_SensorState state) {
  sensornet_SensorStatus st;
  memset(&st, 0, sizeof st);
  st.sensor_id = s.sensor;
  st.run_id = (char*)s.book.run_id;
  st.state = state;
  st.episode = s.running ? s.now.episode : 0;
  const struct run_version* v = run_book_in_force(&s.book, st.episode, 0.0);
  st.schedule_version = v != NULL ? v->number : 0;
  st.sent_in_episode = s.running ? s.seq : 0;
  st.sent_total = s.sent_total;
  st.process_id = (int32_t)getpid();
  st.wall_time_ns = run_wall_ns();
  st.detail = "";
  (void)dds_write(writer, &st);
}

static void take_controls(dds_entity_t reader) {
  void* samples[8] = {NULL};
  dds_sample_info_t infos[8];
  const int n = dds_take(reader, samples, infos, 8, 8);
  for (int i = 0; i < n; ++i) {
    const sensornet_EpisodeControl* c = samples[i];
    if (!infos[i].valid_data || strcmp(c->run_id, s.book.run_id) != 0) continue;
    for (uint32_t k = 0; k < c->failed_sensors._length; ++k) {
      if (c->failed_sensors._buffer[k] == s.sensor) s.failed = 1; /* dead: publishes nothing */
    }
    if (c->command == sensornet_RUN_SHUTDOWN) s.shutdown = 1;
    if (c->command == sensornet_EPISODE_START && s.start_count < MAX_STARTS) {
      s.starts[s.start_count++] = (struct start){c->episode, c->start_wall_time_ns, c->time_scale};
    }
  }
  if (n > 0) dds_return_loan(reader, samples, n);
}

static void usage(void) {
  fprintf(stderr,
          "usage: external_sensor --run-id ID --sensor J [--dim P] [--domain-id D] [--seed S]\n"
          "                       [--measure truth|zero]\n");
  exit(2);
}

int main(int argc, char** argv) {
  dds_domainid_t domain = DDS_DOMAIN_DEFAULT;
  s.rng = 88172645463325252ULL;
  s.as_ours = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (strcmp(argv[i], "--run-id") == 0)
      s.book.run_id = argv[i + 1];
    else if (strcmp(argv[i], "--sensor") == 0)
      s.sensor = (uint32_t)strtoul(argv[i + 1], NULL, 10);
    else if (strcmp(argv[i], "--dim") == 0)
      s.dim = (uint32_t)strtoul(argv[i + 1], NULL, 10);
    else if (strcmp(argv[i], "--domain-id") == 0)
      domain = (dds_domainid_t)strtoul(argv[i + 1], NULL, 10);
    else if (strcmp(argv[i], "--seed") == 0) {
      s.rng ^= strtoull(argv[i + 1], NULL, 10) * 0x9E3779B97F4A7C15ULL;
      s.as_ours = 0;
    } else if (strcmp(argv[i], "--measure") == 0 && strcmp(argv[i + 1], "truth") == 0)
      s.zero = 0;
    else if (strcmp(argv[i], "--measure") == 0 && strcmp(argv[i + 1], "zero") == 0)
      s.zero = 1;
    else
      usage();
  }
  if (s.book.run_id == NULL || s.dim > MAX_DIM) usage();

  char run[256], mine[300];
  snprintf(run, sizeof run, "sensornet/%s", s.book.run_id);
  snprintf(mine, sizeof mine, "sensornet/%s/sensors/%u", s.book.run_id, s.sensor);
  const dds_entity_t participant = dds_create_participant(domain, NULL, NULL);
  if (participant < 0) {
    fprintf(stderr, "external_sensor: cannot join DDS domain: %s\n", dds_strretcode(participant));
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

  q = run_qos(mine); /* Measurement: reliable, keep-all, volatile, liveliness 1 s */
  dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  dds_qset_liveliness(q, DDS_LIVELINESS_AUTOMATIC, DDS_SECS(1));
  dds_qset_writer_data_lifecycle(q, false);
  const dds_entity_t measurements = dds_create_writer(participant, t_measurement, q, NULL);
  dds_delete_qos(q);
  q = run_last_known_qos(mine, 16);
  dds_qset_writer_data_lifecycle(q, false);
  const dds_entity_t tallies = dds_create_writer(participant, t_tally, q, NULL);
  dds_delete_qos(q);
  q = run_last_known_qos(mine, 1);
  dds_qset_liveliness(q, DDS_LIVELINESS_AUTOMATIC, DDS_SECS(1));
  dds_qset_writer_data_lifecycle(q, false);
  const dds_entity_t statuses = dds_create_writer(participant, t_status, q, NULL);
  dds_delete_qos(q);

  sensornet_SensorState said = sensornet_SENSOR_STARTING;
  int64_t next_status_ns = 0;
  double z[MAX_DIM] = {0};
  while (!s.shutdown) {
    run_book_take_scenario(&s.book, scenarios, 0, "external_sensor");
    if (s.book.have_scenario && s.sensor >= s.book.sensors) {
      fprintf(stderr, "external_sensor: --sensor %u: the scenario has %u sensors\n", s.sensor,
              s.book.sensors);
      return 2;
    }
    if (s.book.have_scenario && s.world == NULL) {
      char why[256];
      s.world = sn_world_open(s.book.yaml, s.book.seed, why, sizeof why);
      if (s.world == NULL) {
        fprintf(stderr, "external_sensor: the run's scenario: %s\n", why);
        return 2;
      }
      const uint32_t p = sn_world_measurement_dim(s.world, s.sensor);
      if ((s.dim != 0 && s.dim != p) || p > MAX_DIM) {
        fprintf(stderr, "external_sensor: --dim %u: sensor %u measures %u values\n", s.dim,
                s.sensor, p);
        return 2;
      }
      s.dim = p;
    }
    if (s.book.have_scenario && s.as_ours && (s.book.has_network || s.book.timetable)) {
      fprintf(stderr,
              "external_sensor: run %s %s; this example draws Poisson arrivals as "
              "sensornet's agents do only without them (give --seed for a draw of its own)\n",
              s.book.run_id,
              s.book.has_network ? "emulates a network (network:)" : "has timetable arrivals");
      return 2;
    }
    run_book_take_schedules(&s.book, schedules);
    take_controls(controls);
    const int64_t now = run_wall_ns();
    if (!s.running && !s.failed && s.book.have_scenario && s.start_count > 0) {
      s.now = s.starts[0]; /* the earliest announced: starts come in order */
      memmove(&s.starts[0], &s.starts[1], sizeof(struct start) * (size_t)(--s.start_count));
      s.running = 1;
      s.seq = 0;
      if (s.as_ours) {
        draw_as_ours();
      } else {
        s.next_t = run_book_next_arrival(&s.book, s.now.episode, 0.0, s.sensor, uniform, NULL);
      }
    }
    if (s.running && !s.failed) {
      if (s.as_ours && s.drawn_with != s.book.version_count) draw_as_ours();
      const double emulated = (double)(now - s.now.start_ns) * 1e-9 * s.now.time_scale;
      uint32_t version = 0;
      double at;
      while ((at = next_instant(&version)) <= s.book.horizon_s && at <= emulated) {
        sensornet_Measurement m;
        memset(&m, 0, sizeof m);
        m.sensor_id = s.sensor;
        m.run_id = (char*)s.book.run_id;
        m.episode = s.now.episode;
        m.seq = s.seq;
        m.emulated_time_s = at;
        m.schedule_version = version;
        if (!s.zero && sn_world_measure(s.world, s.now.episode, s.sensor, s.seq, at, z) != 0) {
          fprintf(stderr, "external_sensor: %s\n", sn_world_error(s.world));
          return 1;
        }
        m.publish_wall_time_ns = run_wall_ns();
        m.z._length = m.z._maximum = s.dim;
        m.z._buffer = z;
        m.z._release = false;
        while (dds_write(measurements, &m) == DDS_RETCODE_TIMEOUT) {
        } /* keep-all: a full history waits for the reader, nothing is dropped */
        ++s.seq;
        ++s.sent_total;
        if (!s.as_ours) {
          s.next_t =
              run_book_next_arrival(&s.book, s.now.episode, s.next_t, s.sensor, uniform, NULL);
        }
      }
      if (emulated >= s.book.horizon_s) {
        sensornet_EpisodeTally t;
        memset(&t, 0, sizeof t);
        t.sensor_id = s.sensor;
        t.run_id = (char*)s.book.run_id;
        t.episode = s.now.episode;
        t.sent = s.seq;
        t.finished = true;
        t.process_id = (int32_t)getpid();
        t.wall_time_ns = run_wall_ns();
        (void)dds_write(tallies, &t);
        s.running = 0;
      }
    } else if (s.failed) {
      s.running = 0;
    }
    sensornet_SensorState state = sensornet_SENSOR_STARTING;
    if (s.running) {
      state = sensornet_SENSOR_RUNNING;
    } else if (s.book.have_scenario && s.book.version_count > 0 &&
               run_matched_readers(measurements) > 0 && run_matched_readers(tallies) > 0 &&
               run_matched_writers(controls) > 0) {
      state = sensornet_SENSOR_READY;
    }
    if (state != said || now >= next_status_ns) {
      publish_status(statuses, state);
      said = state;
      next_status_ns = now + 500000000;
    }
    dds_sleepfor(DDS_MSECS(1));
  }
  publish_status(statuses, sensornet_SENSOR_STOPPED);
  dds_sleepfor(DDS_MSECS(200));
  (void)dds_wait_for_acks(tallies, DDS_SECS(2));
  dds_delete(participant);
  run_book_free(&s.book);
  sn_world_close(s.world);
  printf("external_sensor: sensor %u sent %llu measurements\n", s.sensor,
         (unsigned long long)s.sent_total);
  return 0;
}
