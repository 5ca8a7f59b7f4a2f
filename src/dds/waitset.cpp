#include "sensornet/dds/waitset.hpp"

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/dds_error.hpp"

namespace sensornet::dds {
namespace {

dds_duration_t toDuration(std::chrono::nanoseconds span) {
  return span.count() < 0 ? 0 : span.count();
}

// steady_clock::now() + timeout without overflow for "forever" (nanoseconds::max()).
std::chrono::steady_clock::time_point deadlineAfter(std::chrono::nanoseconds timeout) {
  const auto now = std::chrono::steady_clock::now();
  if (timeout >= std::chrono::steady_clock::time_point::max() - now) {
    return std::chrono::steady_clock::time_point::max();
  }
  return now + timeout;
}

// Restores an entity's status mask when the scope ends.
class StatusMaskScope {
 public:
  StatusMaskScope(const Entity& entity, std::uint32_t mask) : entity_(entity) {
    check(entity.api().get_status_mask(entity.handle(), &saved_), "dds_get_status_mask");
    check(entity.api().set_status_mask(entity.handle(), mask), "dds_set_status_mask");
  }
  StatusMaskScope(const StatusMaskScope&) = delete;
  StatusMaskScope& operator=(const StatusMaskScope&) = delete;
  ~StatusMaskScope() { (void)entity_.api().set_status_mask(entity_.handle(), saved_); }

 private:
  const Entity& entity_;
  std::uint32_t saved_ = 0;
};

}  // namespace

ReadCondition::ReadCondition(const detail::ReaderCore& reader, std::uint32_t mask)
    : Entity(reader.api(), check(reader.api().create_readcondition(reader.handle(), mask),
                                 "dds_create_readcondition")) {}

WaitSet::WaitSet(const Participant& participant)
    : waitset_(participant.api(),
               check(participant.api().create_waitset(participant.handle()), "dds_create_waitset")),
      guard_(participant.api(), check(participant.api().create_guardcondition(participant.handle()),
                                      "dds_create_guardcondition")) {
  check(waitset_.api().waitset_attach(waitset_.handle(), guard_.handle(), kWakeToken),
        "dds_waitset_attach");
}

void WaitSet::attach(const Entity& entity, dds_attach_t token) {
  if (token == kWakeToken) throw InputError("waitset", "token", "any value but kWakeToken");
  check(waitset_.api().waitset_attach(waitset_.handle(), entity.handle(), token),
        "dds_waitset_attach");
  ++attached_;
}

void WaitSet::detach(const Entity& entity) {
  check(waitset_.api().waitset_detach(waitset_.handle(), entity.handle()), "dds_waitset_detach");
  --attached_;
}

WaitResult WaitSet::wait(std::chrono::nanoseconds timeout) {
  std::vector<dds_attach_t> tokens(attached_ + 1);
  const dds_return_t count = check(waitset_.api().waitset_wait(waitset_.handle(), tokens.data(),
                                                               tokens.size(), toDuration(timeout)),
                                   "dds_waitset_wait");
  tokens.resize(std::min(tokens.size(), static_cast<std::size_t>(count)));
  WaitResult result;
  for (dds_attach_t token : tokens) {
    if (token == kWakeToken) {
      bool was_set = false;
      check(guard_.api().take_guardcondition(guard_.handle(), &was_set), "dds_take_guardcondition");
      result.woken = true;
    } else {
      result.tokens.push_back(token);
    }
  }
  return result;
}

void WaitSet::wake() {
  check(guard_.api().set_guardcondition(guard_.handle(), true), "dds_set_guardcondition");
}

bool waitForStatus(const Entity& entity, dds_entity_t participant, std::uint32_t status_mask,
                   const std::function<bool()>& done, std::chrono::nanoseconds timeout) {
  const CApi& api = entity.api();
  const auto deadline = deadlineAfter(timeout);
  StatusMaskScope mask(entity, status_mask);
  Entity waitset(api, check(api.create_waitset(participant), "dds_create_waitset"));
  check(api.waitset_attach(waitset.handle(), entity.handle(), 0), "dds_waitset_attach");
  for (;;) {
    if (done()) return true;
    const auto remaining = deadline - std::chrono::steady_clock::now();
    if (remaining <= std::chrono::nanoseconds::zero()) return false;
    check(api.waitset_wait(waitset.handle(), nullptr, 0, toDuration(remaining)),
          "dds_waitset_wait");
  }
}

}  // namespace sensornet::dds
