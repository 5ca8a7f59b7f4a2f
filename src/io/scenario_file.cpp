#include "sensornet/io/scenario_file.hpp"
