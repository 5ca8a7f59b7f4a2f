/* What both C examples share (docs/wire-protocol.md): the clock, the QoS of the run's topics as
 * include/sensornet/dds/topics.hpp chooses them, and the schedule book (schedule_book.h) filled
 * from Cyclone's samples. Plain C against Cyclone DDS's C API and the generated sensornet.h. */
#ifndef SENSORNET_EXAMPLES_RUN_TOPICS_H
#define SENSORNET_EXAMPLES_RUN_TOPICS_H

#include <dds/dds.h>
#include <stdint.h>

#include "schedule_book.h"
#include "sensornet.h"

/* CLOCK_REALTIME in nanoseconds since the epoch: the *_wall_time_ns of every topic. */
int64_t run_wall_ns(void);

/* Reliable (writers block up to 100 ms), in one partition; volatile, keep last 1. */
dds_qos_t* run_qos(const char* partition);
/* Reliable, transient-local, keep last `depth`, the durability service the same: what a late
 * joiner must still get (Scenario 1, Schedule 16, EpisodeControl 8, EpisodeTally 16, ...). */
dds_qos_t* run_last_known_qos(const char* partition, int32_t depth);

int run_matched_readers(dds_entity_t writer);
int run_matched_writers(dds_entity_t reader);

/* Takes what the Scenario and Schedule readers hold for book->run_id into the book; a Scenario
 * of a sensor count other than `sensors_expected` (0: any) is a one-line error and exit 2. */
void run_book_take_scenario(struct run_book* book, dds_entity_t reader, uint32_t sensors_expected,
                            const char* program);
void run_book_take_schedules(struct run_book* book, dds_entity_t reader);

#endif
