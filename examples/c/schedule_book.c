#include "schedule_book.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void run_book_set_scenario(struct run_book* book, double horizon_s, uint32_t intervals,
                           uint32_t sensors, uint32_t state_dim, const char* yaml) {
  book->horizon_s = horizon_s;
  book->intervals = intervals;
  book->sensors = sensors;
  book->state_dim = state_dim;
  book->has_network = strncmp(yaml, "network:", 8) == 0 || strstr(yaml, "\nnetwork:") != NULL;
  book->have_scenario = 1;
}

int run_book_add_version(struct run_book* book, uint32_t number, uint32_t effective_episode,
                         double effective_time_s, double bracket_lower, double bracket_upper,
                         uint32_t intervals, uint32_t sensors, const double* rates, size_t count) {
  if (book->version_count == RUN_MAX_VERSIONS || count != (size_t)intervals * sensors) return 0;
  struct run_version* v = &book->versions[book->version_count++];
  v->number = number;
  v->effective_episode = effective_episode;
  v->effective_time_s = effective_time_s;
  v->bracket_lower = bracket_lower;
  v->bracket_upper = bracket_upper;
  v->rates = malloc(sizeof(double) * count);
  memcpy(v->rates, rates, sizeof(double) * count);
  return 1;
}

const struct run_version* run_book_in_force(const struct run_book* book, uint32_t episode,
                                            double t) {
  const struct run_version* best = NULL;
  for (int i = 0; i < book->version_count; ++i) {
    const struct run_version* v = &book->versions[i];
    const int effective = v->effective_episode < episode ||
                          (v->effective_episode == episode && v->effective_time_s <= t);
    if (effective && (best == NULL || v->number > best->number)) best = v;
  }
  return best;
}

double run_book_rate(const struct run_book* book, uint32_t episode, double t, uint32_t j) {
  const struct run_version* v = run_book_in_force(book, episode, t);
  if (v == NULL) return 0.0;
  uint32_t i = (uint32_t)(t / (book->horizon_s / book->intervals));
  if (i >= book->intervals) i = book->intervals - 1;
  return v->rates[i * book->sensors + j];
}

double run_book_next_change(const struct run_book* book, uint32_t episode, double t) {
  const double width = book->horizon_s / book->intervals;
  double end = (floor(t / width + 1e-12) + 1.0) * width;
  for (int i = 0; i < book->version_count; ++i) {
    const struct run_version* v = &book->versions[i];
    if (v->effective_episode == episode && v->effective_time_s > t && v->effective_time_s < end) {
      end = v->effective_time_s;
    }
  }
  return end > book->horizon_s ? book->horizon_s : end;
}

double run_book_next_arrival(const struct run_book* book, uint32_t episode, double t, uint32_t j,
                             double (*uniform)(void*), void* state) {
  double budget = -log(uniform(state)); /* Exp(1) of integrated rate */
  while (t < book->horizon_s) {
    const double end = run_book_next_change(book, episode, t);
    const double rate = run_book_rate(book, episode, t, j);
    if (rate * (end - t) >= budget) return t + budget / rate;
    budget -= rate * (end - t);
    t = end;
  }
  return INFINITY;
}
