// sensor_agent: emulates one sensor, or a block of sensors, of a sensornet run (docs/ARCHITECTURE.md,
// "Processes"). It needs only the run id and its sensor ids; the scenario, the schedule and
// the episodes come over DDS.

#include "sensor_agent.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/sensor_ids.hpp"
#include "sensornet/io/command_line.hpp"

int main(int argc, char** argv) {
  return sensornet::runProgram("sensor_agent", [&] {
    sensornet::configureLogging("sensor_agent");
    CLI::App app{
        "sensornet sensor agent: emulates sensors of a running emulation. It learns the "
        "scenario and the schedule over DDS, and for every episode publishes each sensor's "
        "measurements z = H_j x(t) + v_j at Poisson arrival instants of the schedule in force, "
        "on the emulated clock. Example:\n  sensor_agent --run-id demo --sensors 0-5"};
    app.name("sensor_agent");
    sensornet::sensor_agent::AgentOptions options;
    sensornet::wire::addRunOptions(app, options.run);
    std::string sensors;
    app.add_option("--sensors", sensors,
                   "the sensor ids (0-based) this process emulates: 3, 0-9 or 0,2,5-7")
        ->required();
    app.add_option("--status-period", options.status_period_s,
                   "seconds between SensorStatus samples when nothing changes")
        ->capture_default_str()
        ->check(sensornet::positiveNumber(sensornet::kMaxWallSeconds));
    if (auto code = sensornet::parseCommandLine(app, argc, argv)) return *code;
    options.sensors = sensornet::emulator::parseSensorIds(sensors, "--sensors");
    options.run.security_identity = {sensornet::dds::SecurityRole::Sensor,
                                     sensornet::emulator::formatSensorIds(options.sensors)};
    (void)options.run.domainConfig();  // bad run or domain id: one line, exit 2, before DDS
    return sensornet::sensor_agent::runSensorAgent(options);
  });
}
