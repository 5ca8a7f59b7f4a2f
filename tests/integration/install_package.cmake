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
# A user's C program against the world library, found by pkg-config alone (`pc_dir` on
# PKG_CONFIG_PATH), built as `exe` and run with `run_env` (cmake -E env assignments).
function(check_world_client what pc_dir exe run_env)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env PKG_CONFIG_PATH=${pc_dir}
                          pkg-config --cflags --libs sensornet-world
                  RESULT_VARIABLE rc OUTPUT_VARIABLE flags OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pkg-config sensornet-world (${what}) failed (${rc})")
  endif()
  separate_arguments(flags UNIX_COMMAND "${flags}")
  execute_process(COMMAND cc -std=c11 -Wall -Werror ${CLIENT} -o ${exe} ${flags} -lm
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "building a C program against the ${what} world library failed (${rc}):\n${err}")
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -E env ${run_env} ${exe} ${SCENARIO}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the C program against the ${what} world library failed (${rc}):\n${err}")
  endif()
endfunction()

file(GLOB_RECURSE pc_files ${WORK}/prefix/*/sensornet-world.pc)
if(NOT pc_files)
  message(FATAL_ERROR "the install has no sensornet-world.pc")
endif()
list(GET pc_files 0 pc_file)
get_filename_component(pc_dir ${pc_file} DIRECTORY)
get_filename_component(lib_dir ${pc_dir} DIRECTORY)
check_world_client(installed ${pc_dir} ${WORK}/world_client LD_LIBRARY_PATH=${lib_dir})
# The same program against the build tree, uninstalled: its -uninstalled.pc, run by its rpath.
check_world_client(uninstalled ${BUILD_DIR}/src/world ${WORK}/world_client_tree "")
file(REMOVE_RECURSE ${WORK})
