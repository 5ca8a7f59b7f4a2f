#include "sensornet/io/utc_time.hpp"

#include <cstdio>
#include <ctime>

namespace sensornet {

std::string utcText(std::chrono::system_clock::time_point when, UtcForm form) {
  using std::chrono::duration_cast;
  using std::chrono::milliseconds;
  const auto since_epoch = duration_cast<milliseconds>(when.time_since_epoch()).count();
  auto seconds = since_epoch / 1000;
  auto millis = since_epoch % 1000;
  if (millis < 0) {  // before 1970: the second below, and the milliseconds after it
    millis += 1000;
    seconds -= 1;
  }
  const auto t = static_cast<std::time_t>(seconds);
  std::tm utc{};
  ::gmtime_r(&t, &utc);
  char text[48];
  const std::size_t n = std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
  std::string out(text, n);
  switch (form) {
    case UtcForm::Seconds:
      return out + "Z";
    case UtcForm::Milliseconds: {
      char fraction[8];
      std::snprintf(fraction, sizeof fraction, ".%03dZ", static_cast<int>(millis));
      return out + fraction;
    }
    case UtcForm::NoZone:
      return out;
  }
  return out;
}

std::string utcNow() { return utcText(std::chrono::system_clock::now()); }

}  // namespace sensornet
