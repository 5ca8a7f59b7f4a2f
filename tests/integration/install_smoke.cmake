# Installs the build into a scratch prefix and runs the installed programs once each.
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${PREFIX}
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc})")
endif()
execute_process(COMMAND ${PREFIX}/bin/coordinator timetable --sigma2 1 --horizon 1 --v0 0.5
                        --variances 1,2 --json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0 OR NOT out MATCHES "\"instants\"")
  message(FATAL_ERROR "installed coordinator failed (${rc}): ${out}")
endif()
execute_process(COMMAND ${PREFIX}/bin/fusion_center evaluate --scenario ${SCENARIO} --runs 50
                        --json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(NOT rc EQUAL 0 OR NOT out MATCHES "\"bracket\"")
  message(FATAL_ERROR "installed fusion_center failed (${rc}): ${out}")
endif()
file(REMOVE_RECURSE ${PREFIX})
