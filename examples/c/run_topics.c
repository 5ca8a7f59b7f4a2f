#include "run_topics.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

int64_t run_wall_ns(void) {
  struct timespec t;
  clock_gettime(CLOCK_REALTIME, &t);
  return (int64_t)t.tv_sec * 1000000000 + t.tv_nsec;
}

dds_qos_t* run_qos(const char* partition) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_partition1(q, partition);
  return q;
}

dds_qos_t* run_last_known_qos(const char* partition, int32_t depth) {
  dds_qos_t* q = run_qos(partition);
  dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_durability_service(q, 0, DDS_HISTORY_KEEP_LAST, depth, DDS_LENGTH_UNLIMITED,
                              DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
  return q;
}

int run_matched_readers(dds_entity_t writer) {
  dds_publication_matched_status_t m;
  return dds_get_publication_matched_status(writer, &m) == 0 ? (int)m.current_count : 0;
}

int run_matched_writers(dds_entity_t reader) {
  dds_subscription_matched_status_t m;
  return dds_get_subscription_matched_status(reader, &m) == 0 ? (int)m.current_count : 0;
}

void run_book_take_scenario(struct run_book* book, dds_entity_t reader, uint32_t sensors_expected,
                            const char* program) {
  void* samples[4] = {NULL};
  dds_sample_info_t infos[4];
  const int n = dds_take(reader, samples, infos, 4, 4);
  for (int i = 0; i < n; ++i) {
    const sensornet_Scenario* sc = samples[i];
    if (!infos[i].valid_data || strcmp(sc->run_id, book->run_id) != 0) continue;
    if (sensors_expected != 0 && sc->sensor_count != sensors_expected) {
      fprintf(stderr, "%s: the scenario of run %s has %u sensors, the command line describes %u\n",
              program, book->run_id, sc->sensor_count, sensors_expected);
      exit(2);
    }
    run_book_set_scenario(book, sc->horizon_s, sc->intervals, sc->sensor_count, sc->state_dim,
                          sc->seed, sc->yaml, sc->arrivals);
  }
  if (n > 0) dds_return_loan(reader, samples, n);
}

void run_book_take_schedules(struct run_book* book, dds_entity_t reader) {
  void* samples[16] = {NULL};
  dds_sample_info_t infos[16];
  const int n = dds_take(reader, samples, infos, 16, 16);
  for (int i = 0; i < n; ++i) {
    const sensornet_Schedule* sc = samples[i];
    if (!infos[i].valid_data || strcmp(sc->run_id, book->run_id) != 0) continue;
    (void)run_book_add_version(book, sc->version, sc->effective_episode, sc->effective_time_s,
                               sc->bracket_lower, sc->bracket_upper, sc->intervals,
                               sc->sensor_count, sc->rates_hz._buffer, sc->rates_hz._length);
  }
  if (n > 0) dds_return_loan(reader, samples, n);
}
