# The installed CMake package as a user's project sees it: install the build into a scratch
# prefix, configure examples/testing_gtest against it with find_package(sensornet), build it and
# run its GoogleTest suite (which launches real runs with sensornet::testing).
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK}/prefix
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc})")
endif()
foreach(installed include/sensornet/testing/installed.hpp include/sensornet/testing/launched_run.hpp
                  share/sensornet/scenarios/default.yaml bin/sensornet)
  if(NOT EXISTS ${WORK}/prefix/${installed})
    message(FATAL_ERROR "the install has no ${installed}")
  endif()
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${EXAMPLE} -B ${WORK}/build -G Ninja
                        -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_BUILD_TYPE=Release
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the example against the package failed (${rc}):\n${out}\n${err}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK}/build
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the example failed (${rc}):\n${out}\n${err}")
endif()
execute_process(COMMAND ${WORK}/build/my_sensornet_tests
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the example's tests failed (${rc}):\n${err}")
endif()
file(REMOVE_RECURSE ${WORK})
