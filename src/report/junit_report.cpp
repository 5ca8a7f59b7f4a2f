#include "sensornet/report/junit_report.hpp"

#include <map>

#include "sensornet/core/xml_text.hpp"
#include "sensornet/report/svg_plot.hpp"

namespace sensornet::report {
namespace {

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

std::string junitSuiteXml(const std::string& suite, const std::string& classname,
                          const std::vector<JunitCase>& cases, double seconds) {
  std::size_t failures = 0;
  for (const JunitCase& c : cases) failures += c.pass ? 0 : 1;
  std::string xml = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n  <testsuite name=\"" +
                    escapeXml(suite) + "\" tests=\"" + std::to_string(cases.size()) +
                    "\" failures=\"" + std::to_string(failures) + "\" errors=\"0\" time=\"" +
                    formatTick(seconds) + "\">\n";
  for (const JunitCase& c : cases) {
    xml += "    <testcase classname=\"" + escapeXml(classname) + "\" name=\"" +
           escapeXml(c.name) + "\"";
    xml += c.pass ? "><system-out>" + escapeXml(c.message) + "</system-out></testcase>\n"
                  : "><failure message=\"" + escapeXml(c.failure) + "\" type=\"" +
                        escapeXml(c.name) + "\">" + escapeXml(c.message) + "</failure></testcase>\n";
  }
  return xml + "  </testsuite>\n</testsuites>\n";
}

std::string junitXml(const JunitRun& run) {
  const bool completed = run.status == RunStatus::Completed;
  const std::string outcome = "status " + std::string(wordOf(run.status)) + ", exit " +
                              std::to_string(run.exit_code) + ", " + faultSummary(run.faults);
  std::vector<JunitCase> cases = {{"run", completed, outcome, outcome}};
  for (const RequirementCheck& c : run.checks) {
    cases.push_back({"require " + c.requirement.text, c.pass, "measured " + c.measured, describe(c)});
  }
  return junitSuiteXml("sensornet run " + run.run_id, "sensornet." + run.run_id, cases,
                       run.seconds);
}

}  // namespace sensornet::report
