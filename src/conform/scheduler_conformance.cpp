// The rules of a scheduler's (an operator's) role, judged from the Commands and CommandReplies
// of a run whose coordinator left the first copy of each command unanswered
// (--drop-first-command-copy): a reply to a command proves that it was written again, and the
// intervals between its recorded copies say how soon.
#include <fmt/format.h>

#include <algorithm>
#include <map>

#include "rules.hpp"
#include "sensornet/conform/sensor_conformance.hpp"
#include "sensornet/emulator/run_partitions.hpp"

namespace sensornet::conform {
namespace {

using namespace detail;

constexpr const char* kSection = "commands-and-replies";
constexpr const char* kNoReply = "no reply came to judge by (see retries)";

// One command as the run saw it: its copies in the order written, and its first reply.
struct Exchange {
  std::vector<const RecordedCommand*> copies;
  const RecordedReply* reply = nullptr;
};

// The launcher's own failure notices are not the program's.
bool fromTheLauncher(const RecordedCommand& c, const std::string& launcher_partition) {
  return c.partition == launcher_partition &&
         c.command.kind == emulator::CommandKind::SensorsFailed &&
         c.command.issuer.starts_with("sensornet launch ");
}

struct Exchanges {
  std::map<std::uint64_t, Exchange> by_id;
  std::vector<std::uint64_t> order;  // ids by their first copy
};

Exchanges exchangesOf(const RecordedRun& run) {
  const std::string launcher =
      emulator::commandPartition("sensornet/" + run.run_id, emulator::CommandSender::Launcher);
  Exchanges out;
  for (const RecordedCommand& c : run.commands) {
    if (fromTheLauncher(c, launcher)) continue;
    Exchange& e = out.by_id[c.command.command_id];
    if (e.copies.empty()) out.order.push_back(c.command.command_id);
    e.copies.push_back(&c);
  }
  for (auto& [id, e] : out.by_id) {  // in the order they were written
    std::stable_sort(e.copies.begin(), e.copies.end(),
                     [](const auto* a, const auto* b) { return a->written_ns < b->written_ns; });
  }
  for (const RecordedReply& r : run.replies) {
    const auto e = out.by_id.find(r.command_id);
    if (e == out.by_id.end()) continue;
    const RecordedReply*& first = e->second.reply;
    if (first == nullptr || r.written_ns < first->written_ns) first = &r;
  }
  return out;
}

// A rule over the commands holds when there were some and no offence was found (`first`, the
// first one); `fine` is its evidence then.
RuleCheck conclude(RuleCheck r, const Exchanges& exchanges, std::string first, std::string fine) {
  r.pass = first.empty() && !exchanges.order.empty();
  r.evidence = !first.empty()            ? std::move(first)
               : exchanges.order.empty() ? std::string("no Command to judge")
                                         : std::move(fine);
  return r;
}

// "command 1733... (COMMAND_REPLAN)"
std::string named(const RecordedCommand& c) {
  return fmt::format("command {} ({})", c.command.command_id, c.kind);
}

RuleCheck commands(const RecordedRun& run, const Exchanges& exchanges) {
  RuleCheck r = rule("commands", "writes at least one Command to the run", kSection);
  r.pass = !exchanges.order.empty();
  if (!r.pass) {
    r.evidence = "no Command was recorded";
    return r;
  }
  std::map<std::string, int> kinds;
  for (const std::uint64_t id : exchanges.order) {
    ++kinds[exchanges.by_id.at(id).copies.front()->kind];
  }
  std::string listed;
  for (const auto& [kind, n] : kinds) {
    listed += fmt::format("{}{} {}", listed.empty() ? "" : ", ", n, kind);
  }
  r.evidence = fmt::format("{} ({}), {} written, the first at {:+.3f} s",
                           plural(exchanges.order.size(), "command", "commands"), listed,
                           plural(run.commands.size(), "copy", "copies"),
                           secondsSince(run.first_ns, run.commands.front().written_ns));
  return r;
}

RuleCheck byRight(const RecordedRun& run, const Exchanges& exchanges) {
  RuleCheck r = rule("by-right",
                     "writes each Command in the operator's partition P/operator, and no "
                     "COMMAND_SENSORS_FAILED (the launcher's alone)",
                     kSection);
  const std::string operator_partition =
      emulator::commandPartition("sensornet/" + run.run_id, emulator::CommandSender::Operator);
  std::string first;
  for (const std::uint64_t id : exchanges.order) {
    const Exchange& e = exchanges.by_id.at(id);
    for (const RecordedCommand* c : e.copies) {
      if (c->partition != operator_partition) {
        first = fmt::format("{} written in '{}'", named(*c), c->partition);
      } else if (c->command.kind == emulator::CommandKind::SensorsFailed) {
        first = named(*c) + " is the launcher's to send";
      }
      if (!first.empty()) break;
    }
    if (first.empty() && e.reply != nullptr && e.reply->reason.starts_with("not permitted")) {
      first = fmt::format("{} refused: {}", named(*e.copies.front()), e.reply->reason);
    }
    if (!first.empty()) break;
  }
  return conclude(std::move(r), exchanges, first, "all in " + operator_partition);
}

RuleCheck ids(const RecordedRun& run, const Exchanges& exchanges) {
  RuleCheck r = rule("command-ids",
                     "names the run in each Command and gives each command an id of its own "
                     "(every copy of an id asks the same)",
                     kSection);
  std::string first;
  for (const std::uint64_t id : exchanges.order) {
    const Exchange& e = exchanges.by_id.at(id);
    const emulator::CommandEvent& c = e.copies.front()->command;
    if (id == 0) {
      first = "command id 0";
    } else if (c.run_id != run.run_id) {
      first = fmt::format("{} names run '{}'", named(*e.copies.front()), c.run_id);
    } else {
      for (const RecordedCommand* copy : e.copies) {
        const emulator::CommandEvent& o = copy->command;
        if (o.kind != c.kind || o.surrogate != c.surrogate || o.sensor_ids != c.sensor_ids ||
            o.budget != c.budget || o.schedule_json != c.schedule_json || o.detail != c.detail) {
          first = fmt::format("id {} asks two things: {} and {}", id, e.copies.front()->kind,
                              copy->kind);
          break;
        }
      }
    }
    if (!first.empty()) break;
  }
  return conclude(std::move(r), exchanges, first,
                  plural(exchanges.order.size(), "id", "ids") + ", each of one content");
}

RuleCheck retries(const Exchanges& exchanges) {
  RuleCheck r = rule("retries",
                     fmt::format("writes a command again every 2 s ({:g} to {:g} s) until its "
                                 "reply comes (the coordinator left each first copy unanswered)",
                                 kResendMinS, kResendMaxS),
                     kSection);
  std::string first;
  double shortest = 1e300, longest = 0.0;
  for (const std::uint64_t id : exchanges.order) {
    const Exchange& e = exchanges.by_id.at(id);
    const std::int64_t until = e.reply != nullptr ? e.reply->written_ns : INT64_MAX;
    for (std::size_t i = 1; i < e.copies.size() && e.copies[i]->written_ns <= until; ++i) {
      const double gap = secondsSince(e.copies[i - 1]->written_ns, e.copies[i]->written_ns);
      shortest = std::min(shortest, gap);
      longest = std::max(longest, gap);
      if ((gap < kResendMinS || gap > kResendMaxS) && first.empty()) {
        first = fmt::format("{}: copy {} came {:.3f} s after the one before", named(*e.copies[0]),
                            i + 1, gap);
      }
    }
    if (e.reply == nullptr && first.empty()) {
      first = fmt::format("{}: {} and no reply (never written again after the first was lost?)",
                          named(*e.copies[0]), plural(e.copies.size(), "copy", "copies"));
    }
  }
  const std::string commands = plural(exchanges.order.size(), "command", "commands");
  // With no resend recorded, every first copy was lost before the recorder saw it too: the
  // reply is the evidence.
  return conclude(std::move(r), exchanges, first,
                  longest == 0.0
                      ? commands +
                            " answered, which the coordinator does only for a copy after "
                            "the first"
                      : fmt::format("{} answered after a resend; resent after {:.2f} to {:.2f} s",
                                    commands, shortest, longest));
}

RuleCheck repliesRead(const Exchanges& exchanges) {
  RuleCheck r = rule("replies-read",
                     fmt::format("reads the CommandReply: writes no copy of a command more than "
                                 "{:g} s after its reply",
                                 kReplySlackS),
                     kSection);
  std::string first;
  std::size_t replied = 0;
  for (const std::uint64_t id : exchanges.order) {
    const Exchange& e = exchanges.by_id.at(id);
    if (e.reply == nullptr) continue;
    ++replied;
    const auto late = std::find_if(e.copies.begin(), e.copies.end(), [&](const auto* c) {
      return secondsSince(e.reply->written_ns, c->written_ns) > kReplySlackS;
    });
    if (late != e.copies.end() && first.empty()) {
      first =
          fmt::format("{}: written again {:.3f} s after its reply ({} after it)", named(**late),
                      secondsSince(e.reply->written_ns, (*late)->written_ns),
                      plural(static_cast<std::size_t>(e.copies.end() - late), "copy", "copies"));
    }
  }
  // Unanswered commands fail `retries`; with no reply there is nothing more to read.
  return conclude(std::move(r), exchanges, first,
                  replied == 0
                      ? kNoReply
                      : "no copy after the reply, for " + plural(replied, "command", "commands"));
}

RuleCheck accepted(const Exchanges& exchanges) {
  RuleCheck r = rule("accepted",
                     "sends commands the coordinator accepts (kinds and arguments as the page "
                     "gives them)",
                     kSection);
  std::string first;
  std::size_t answered = 0;
  for (const std::uint64_t id : exchanges.order) {
    const Exchange& e = exchanges.by_id.at(id);
    if (e.reply == nullptr) continue;
    ++answered;
    // A refusal by right is by-right's to tell.
    if (!e.reply->accepted && !e.reply->reason.starts_with("not permitted") && first.empty()) {
      first = fmt::format("{} refused: {}", named(*e.copies[0]), e.reply->reason);
    }
  }
  std::string versions;
  for (const std::uint64_t id : exchanges.order) {
    const RecordedReply* reply = exchanges.by_id.at(id).reply;
    if (reply != nullptr && reply->schedule_version > 0) {
      versions += (versions.empty() ? "" : ", ") + std::to_string(reply->schedule_version);
    }
  }
  return conclude(std::move(r), exchanges, first,
                  answered == 0
                      ? kNoReply
                      : fmt::format("{} accepted{}", plural(answered, "command", "commands"),
                                    versions.empty() ? "" : "; versions " + versions));
}

RuleCheck leaves(const RunFacts& facts) {
  RuleCheck r = rule("leaving",
                     "leaves by itself with exit 0, when its work is done or at the latest on "
                     "RUN_SHUTDOWN",
                     "leaving-the-run");
  r.pass = facts.program_exit == 0;
  r.evidence = "it " + programEnding(facts);
  return r;
}

}  // namespace

std::vector<RuleCheck> checkScheduler(const RecordedRun& run, const RunFacts& facts) {
  const Exchanges exchanges = exchangesOf(run);
  return {
      commands(run, exchanges), byRight(run, exchanges), ids(run, exchanges), retries(exchanges),
      repliesRead(exchanges),   accepted(exchanges),     leaves(facts),       runCompletes(facts)};
}

}  // namespace sensornet::conform
