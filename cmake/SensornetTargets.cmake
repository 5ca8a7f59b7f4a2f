# One place for the compiler flags every sensornet target gets, and one function per target
# kind (library, executable, test, benchmark), so that no target sets flags of its own.

# SENSORNET_NATIVE_ARCH: the code of every sensornet target is compiled for this machine's CPU,
# every target alike, so that Eigen's inline code is the same in all of them; no contraction of
# a * b + c into one rounding, so that results do not depend on the option beyond Eigen's own
# kernels (which use FMA where the CPU has it). On x86 without AVX-512: GCC 12's AVX-512
# intrinsics, inlined into Eigen's kernels, trip -Wmaybe-uninitialized (a false positive in
# avx512fintrin.h) and so -Werror, and AVX2 with FMA gives most of the gain (planning at n = 50,
# M = 1000: 10.2 s portable, 5.3 s AVX2, 4.6 s AVX-512).
# The sanitizer build stays portable: it checks correctness, not speed, and at -O0 Eigen's AVX
# code is slower than its SSE2 code (integration tests that wait for a run timed out).
set(SENSORNET_ARCH_FLAGS "")
if(SENSORNET_NATIVE_ARCH AND NOT SENSORNET_SANITIZE)
  include(CheckCXXCompilerFlag)
  check_cxx_compiler_flag("-march=native -mno-avx512f" SENSORNET_HAS_MARCH_NATIVE_X86)
  if(SENSORNET_HAS_MARCH_NATIVE_X86)
    set(SENSORNET_ARCH_FLAGS -march=native -mno-avx512f -ffp-contract=off)
  else()
    check_cxx_compiler_flag("-march=native" SENSORNET_HAS_MARCH_NATIVE)
    if(SENSORNET_HAS_MARCH_NATIVE)
      set(SENSORNET_ARCH_FLAGS -march=native -ffp-contract=off)
    else()
      message(STATUS "SENSORNET_NATIVE_ARCH: the compiler takes no -march=native; portable code")
    endif()
  endif()
endif()

function(sensornet_target_options target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                           -Wno-sign-conversion)
  if(SENSORNET_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  target_compile_options(${target} PRIVATE ${SENSORNET_ARCH_FLAGS})
  # Release at -O2, after CMake's -O3 (the last -O wins): the code RelWithDebInfo runs.
  target_compile_options(${target} PRIVATE $<$<CONFIG:Release>:-O2>)
  if(SENSORNET_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                                             -fno-sanitize-recover=undefined)
    # PUBLIC: a static library's code needs the runtimes in whatever links it
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
  endif()
endfunction()

# sensornet_add_executable(name SOURCES ... LIBS ...): an installed command-line program.
function(sensornet_add_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS})
  sensornet_target_options(${name})
  install(TARGETS ${name} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()

# sensornet_add_test(name SOURCES ... LIBS ... [LABELS ...]): one GoogleTest executable whose
# tests CTest discovers one by one.
function(sensornet_add_test name)
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  sensornet_target_options(${name})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  # The sanitizer build runs everything about 4 times slower (-O0 and instrumentation): the
  # same factor as kTimeFactor in tests/support/sanitizer.hpp, which scales the tests' own limits.
  if(SENSORNET_SANITIZE)
    math(EXPR ARG_TIMEOUT "${ARG_TIMEOUT} * 4")
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
                       PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}")
endfunction()

# sensornet_add_bench(name SOURCES ... LIBS ...): a benchmark program, built but never run by CTest.
function(sensornet_add_bench name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS})
  sensornet_target_options(${name})
endfunction()

# sensornet_forbid_links(target FORBIDDEN ...): a configure error when `target` links any of the
# FORBIDDEN targets, directly or through the libraries it links (a layer that must not depend on
# another: the emulator's cores on DDS). Call it after every target involved is defined.
function(sensornet_forbid_links target)
  set(seen "")
  set(pending ${target})
  while(pending)
    list(POP_FRONT pending current)
    if(current IN_LIST seen OR NOT TARGET ${current})
      continue()
    endif()
    list(APPEND seen ${current})
    if(current IN_LIST ARGN)
      message(FATAL_ERROR "${target} links ${current}, which its layer must not depend on")
    endif()
    get_target_property(links ${current} LINK_LIBRARIES)
    get_target_property(interface ${current} INTERFACE_LINK_LIBRARIES)
    foreach(link IN LISTS links interface)
      if(link AND NOT link MATCHES "^\\$<")
        list(APPEND pending ${link})
      endif()
    endforeach()
  endwhile()
endfunction()
