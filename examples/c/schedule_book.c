#include "schedule_book.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void run_book_set_scenario(struct run_book* book, double horizon_s, uint32_t intervals,
                           uint32_t sensors, uint32_t state_dim, uint64_t seed, const char* yaml,
                           const char* arrivals) {
  book->seed = seed;
  book->timetable = strcmp(arrivals, "timetable") == 0;
  book->horizon_s = horizon_s;
  book->intervals = intervals;
  book->sensors = sensors;
  book->state_dim = state_dim;
  book->has_network = strncmp(yaml, "network:", 8) == 0 || strstr(yaml, "\nnetwork:") != NULL;
  free(book->yaml);
  const size_t size = strlen(yaml) + 1;
  book->yaml = malloc(size);
  if (book->yaml != NULL) memcpy(book->yaml, yaml, size);
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

void run_book_free(struct run_book* book) {
  for (int i = 0; i < book->version_count; ++i) {
    free(book->versions[i].rates);
    book->versions[i].rates = NULL;
  }
  book->version_count = 0;
  free(book->yaml);
  book->yaml = NULL;
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

/* --- sensornet's own draw ---------------------------------------------------------------- */

#define EMULATED_ARRIVAL_STREAM 0x656d2d6172726976ULL /* "em-arriv" */
#define TICK_LEVELS 20

static uint64_t mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

struct keyed_rng {
  uint64_t s[4];
};

static struct keyed_rng keyed(uint64_t seed, const uint64_t* keys, int count) {
  uint64_t h = mix64(seed);
  for (int i = 0; i < count; ++i) h = mix64(h ^ mix64(keys[i] + 0x632be59bd9b4e019ULL));
  struct keyed_rng r;
  for (int i = 0; i < 4; ++i) {
    h = mix64(h);
    r.s[i] = h;
  }
  return r;
}

static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

static double exponential(struct keyed_rng* r, double rate) {
  uint64_t* s = r->s;
  const uint64_t bits = rotl(s[0] + s[3], 23) + s[0];
  const uint64_t t = s[1] << 17;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = rotl(s[3], 45);
  const double u = ((double)(bits >> 11) + 0.5) * 0x1.0p-53;
  return -log(u) / rate;
}

static int by_time(const void* left, const void* right) {
  const double x = *(const double*)left, y = *(const double*)right;
  return (x > y) - (x < y);
}

size_t run_book_draw_as_ours(const struct run_book* book, uint32_t episode, uint32_t j,
                             double** times, uint32_t** versions) {
  const double T = book->horizon_s, h = T / book->intervals;
  const int n = (int)book->intervals;
  /* The stretches: from 0 and from every effective time inside the episode. */
  double breaks[RUN_MAX_VERSIONS + 1];
  int break_count = 1;
  breaks[0] = 0.0;
  for (int i = 0; i < book->version_count; ++i) {
    const struct run_version* v = &book->versions[i];
    if (v->effective_episode == episode && v->effective_time_s > 0.0 && v->effective_time_s < T) {
      breaks[break_count++] = v->effective_time_s;
    }
  }
  qsort(breaks, (size_t)break_count, sizeof(double), by_time);
  size_t count = 0, capacity = 64;
  *times = malloc(capacity * sizeof(double));
  *versions = malloc(capacity * sizeof(uint32_t));
  const double tick_s = T / (double)(1LL << TICK_LEVELS);
  const struct run_version* previous = NULL;
  for (int b = 0; b < break_count; ++b) {
    if (b > 0 && breaks[b] == breaks[b - 1]) continue;
    const struct run_version* v = run_book_in_force(book, episode, breaks[b]);
    if (v == NULL || v == previous) continue; /* a break that changed nothing joins the stretch */
    previous = v;
    const double from = breaks[b];
    double to = T;
    for (int c = b + 1; c < break_count; ++c) {
      if (run_book_in_force(book, episode, breaks[c]) != v) {
        to = breaks[c];
        break;
      }
    }
    uint64_t from_bits;
    memcpy(&from_bits, &from, sizeof from_bits);
    const uint64_t keys[5] = {EMULATED_ARRIVAL_STREAM, episode, j, v->number, from_bits};
    struct keyed_rng rng = keyed(book->seed, keys, 5);
    int first = (int)floor(from / h);
    first = first < 0 ? 0 : first > n - 1 ? n - 1 : first;
    first = first > 0 ? first - 1 : 0; /* floor(from / h) may round up past from */
    for (int k = first; k < n; ++k) {
      const double start = from > k * h ? from : k * h;
      double end = k + 1 == n ? T : (k + 1) * h;
      if (end > to) end = to;
      if (start >= to) break;
      const double rate = v->rates[k * book->sensors + j];
      if (rate <= 0.0 || start >= end) continue;
      for (double t = start + exponential(&rng, rate); t < end; t += exponential(&rng, rate)) {
        if (count == capacity) {
          capacity *= 2;
          *times = realloc(*times, capacity * sizeof(double));
          *versions = realloc(*versions, capacity * sizeof(uint32_t));
        }
        const double ticks = t > 0.0 ? floor(t / tick_s) : 0.0;
        const double last = (double)(1LL << TICK_LEVELS);
        (*times)[count] = (ticks < last ? ticks : last) * tick_s;
        (*versions)[count] = v->number;
        ++count;
      }
    }
  }
  return count;
}
