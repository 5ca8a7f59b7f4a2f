#include "sensornet/emulator/schedule_book.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>

namespace sensornet {

void to_json(nlohmann::json& j, SurrogateKind kind) { j = std::string(wordOf(kind)); }

}  // namespace sensornet

namespace sensornet::emulator {
namespace {

bool atOrBefore(const ScheduleVersion& v, std::uint32_t episode, double t) {
  return v.effective_episode < episode ||
         (v.effective_episode == episode && v.effective_time_s <= t);
}

}  // namespace

bool identical(const ScheduleVersion& a, const ScheduleVersion& b) {
  const RateSchedule& x = a.schedule;
  const RateSchedule& y = b.schedule;
  return a.version == b.version && a.effective_episode == b.effective_episode &&
         a.effective_time_s == b.effective_time_s && x.horizon() == y.horizon() &&
         x.rates().rows() == y.rates().rows() && x.rates().cols() == y.rates().cols() &&
         x.rates() == y.rates() && a.surrogate == b.surrogate &&
         a.bracket.info == b.bracket.info && a.bracket.cov == b.bracket.cov &&
         a.command_id == b.command_id;
}

ScheduleBook::Outcome ScheduleBook::add(ScheduleVersion v) {
  if (!versions_.empty() && v.version <= versions_.back().version) {
    const auto held =
        std::find_if(versions_.begin(), versions_.end(),
                     [&](const ScheduleVersion& h) { return h.version == v.version; });
    return held != versions_.end() && identical(*held, v) ? Outcome::Duplicate : Outcome::Stale;
  }
  versions_.push_back(std::move(v));
  return Outcome::Accepted;
}

const ScheduleVersion* ScheduleBook::inForce(std::uint32_t episode, double t) const {
  for (auto it = versions_.rbegin(); it != versions_.rend(); ++it) {
    if (atOrBefore(*it, episode, t)) return &*it;
  }
  return nullptr;
}

std::vector<ScheduleSegment> ScheduleBook::segments(std::uint32_t episode,
                                                    double horizon_s) const {
  std::vector<double> breaks = {0.0};
  for (const ScheduleVersion& v : versions_) {
    if (v.effective_episode == episode && v.effective_time_s > 0.0 &&
        v.effective_time_s < horizon_s) {
      breaks.push_back(v.effective_time_s);
    }
  }
  std::sort(breaks.begin(), breaks.end());
  breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
  std::vector<ScheduleSegment> result;
  for (std::size_t i = 0; i < breaks.size(); ++i) {
    const ScheduleVersion* v = inForce(episode, breaks[i]);
    if (v == nullptr) return {};
    const double to = i + 1 < breaks.size() ? breaks[i + 1] : horizon_s;
    if (!result.empty() && result.back().version == v) {
      result.back().to_s = to;  // a later break that changed nothing (a stale effective point)
    } else {
      result.push_back({breaks[i], to, v});
    }
  }
  return result;
}

}  // namespace sensornet::emulator
