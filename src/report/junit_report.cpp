#include "sensornet/report/junit_report.hpp"

#include <map>
#include <optional>

#include "sensornet/core/xml_text.hpp"
#include "sensornet/report/svg_plot.hpp"

namespace sensornet::report {
namespace {

std::string testcase(const std::string& classname, const std::string& name,
                     const std::optional<std::string>& failure, const std::string& message) {
  std::string xml = "    <testcase classname=\"" + escapeXml(classname) + "\" name=\"" +
                    escapeXml(name) + "\"";
  if (!failure) return xml + "><system-out>" + escapeXml(message) + "</system-out></testcase>\n";
  return xml + "><failure message=\"" + escapeXml(*failure) + "\" type=\"" +
         escapeXml(name) + "\">" + escapeXml(message) + "</failure></testcase>\n";
}

// "2 faults: 1 sensor_died, 1 stall" (consequences counted with the rest).
std::string faultSummary(const std::vector<FaultRecord>& faults) {
  if (faults.empty()) return "0 faults";
  std::map<std::string, int> kinds;
  for (const FaultRecord& f : faults) ++kinds[std::string(wordOf(f.kind))];
  std::string text = std::to_string(faults.size()) + (faults.size() == 1 ? " fault: " : " faults: ");
  bool first = true;
  for (const auto& [kind, count] : kinds) {
    text += (first ? "" : ", ") + std::to_string(count) + " " + kind;
    first = false;
  }
  return text;
}

}  // namespace

std::string junitXml(const JunitRun& run) {
  const std::string classname = "sensornet." + run.run_id;
  const bool completed = run.status == RunStatus::Completed;
  std::size_t failures = completed ? 0 : 1;
  for (const RequirementCheck& c : run.checks) failures += c.pass ? 0 : 1;
  const std::string outcome = "status " + std::string(wordOf(run.status)) + ", exit " +
                              std::to_string(run.exit_code) + ", " + faultSummary(run.faults);
  std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n  <testsuite name=\"" +
                    escapeXml("sensornet run " + run.run_id) + "\" tests=\"" +
                    std::to_string(1 + run.checks.size()) + "\" failures=\"" +
                    std::to_string(failures) + "\" errors=\"0\" time=\"" +
                    formatTick(run.seconds) + "\">\n";
  xml += testcase(classname, "run",
                  completed ? std::nullopt : std::optional<std::string>(outcome),
                  outcome);
  for (const RequirementCheck& c : run.checks) {
    const std::string message = describe(c);
    xml += testcase(classname, "require " + c.requirement.text,
                    c.pass ? std::nullopt : std::optional<std::string>("measured " + c.measured),
                    message);
  }
  return xml + "  </testsuite>\n</testsuites>\n";
}

}  // namespace sensornet::report
