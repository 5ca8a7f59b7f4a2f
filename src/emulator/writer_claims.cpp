#include "sensornet/emulator/writer_claims.hpp"

namespace sensornet::emulator {

bool WriterClaims::isForeign(int sensor, WriterId writer, const LivePredicate& live) {
  const auto it = owner_.find(sensor);
  if (it == owner_.end() || it->second == writer) return false;
  if (!live(it->second)) {  // the first writer is gone: the next accepted sample claims anew
    owner_.erase(it);
    return false;
  }
  return true;
}

void WriterClaims::claim(int sensor, WriterId writer) { owner_.try_emplace(sensor, writer); }

void WriterClaims::release(int sensor) { owner_.erase(sensor); }

bool WriterClaims::firstRefusalOf(WriterId writer) { return refused_.insert(writer).second; }

WriterId WriterClaims::ownerOf(int sensor) const {
  const auto it = owner_.find(sensor);
  return it == owner_.end() ? 0 : it->second;
}

}  // namespace sensornet::emulator
