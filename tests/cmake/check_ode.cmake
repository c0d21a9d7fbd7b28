# Configure-time ODE checks (cmake/ErnestOde.cmake), a ctest script:
#   cmake -DMODULE=<ErnestOde.cmake> -DPROJECT_DIR=<tests/cmake/ode_project> -DWORK_DIR=<dir>
#         -DLIBDIR=<ODE's libdir> -DGENERATOR=<generator> -P check_ode.cmake
# An ODE outside the supported versions and a static libode must stop the configuration with a
# message naming what was found and what is needed; the ODE of this machine must pass.
if(DEFINED CASE_VERSION)  # one case of the check alone, in its own process (FATAL_ERROR ends it)
  include(${MODULE})
  ernest_check_ode("${CASE_VERSION}" "${CASE_LIBS}")
  return()
endif()

set(failures 0)
# Runs `command`; `expect_ok` says whether it must succeed; else its output must match `regex`
# (whitespace collapsed: CMake wraps long messages).
function(expect what expect_ok regex)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  string(REGEX REPLACE "[ \t\r\n]+" " " text "${out} ${err}")
  if(expect_ok AND NOT rc EQUAL 0)
    message(SEND_ERROR "${what}: expected success, got ${rc}:\n${out}${err}")
  elseif(NOT expect_ok AND (rc EQUAL 0 OR NOT text MATCHES "${regex}"))
    message(SEND_ERROR "${what}: expected a failure matching '${regex}', got ${rc}:\n${out}${err}")
  else()
    message(STATUS "${what}: as expected")
  endif()
endfunction()

function(expect_check version libs expect_ok regex)
  expect("ODE ${version} (${libs})" ${expect_ok} "${regex}"
         ${CMAKE_COMMAND} -DMODULE=${MODULE} -DCASE_VERSION=${version} "-DCASE_LIBS=${libs}"
         -P ${CMAKE_CURRENT_LIST_FILE})
endfunction()

set(so ${LIBDIR}/libode.so)
set(a ${LIBDIR}/libode.a)
expect_check(0.15.2 "${so}" FALSE "found ODE 0\\.15\\.2, supported ODE >= 0\\.16\\.0 and < 0\\.17")
expect_check(0.17.0 "${so}" FALSE "found ODE 0\\.17\\.0, supported ODE >= 0\\.16\\.0 and < 0\\.17")
expect_check(0.16.2 "${a}" FALSE "static library [^ ]*libode\\.a; ernest needs the shared libode")
expect_check(0.16.2 "${so}" TRUE "")
expect_check(0.16.5 "-lm;${so}" TRUE "")

# The same through pkg-config, on a real configuration: as found here, and with the library
# resolved to the static archive (what a user forcing static linking would get).
file(REMOVE_RECURSE ${WORK_DIR})
expect("configure with this machine's ODE" TRUE ""
       ${CMAKE_COMMAND} -S ${PROJECT_DIR} -B ${WORK_DIR}/shared -G ${GENERATOR}
       -DERNEST_ODE_MODULE=${MODULE})
if(EXISTS ${a})
  expect("configure with pkgcfg_lib_ODE_ode=${a}" FALSE "static library [^ ]*libode\\.a"
         ${CMAKE_COMMAND} -S ${PROJECT_DIR} -B ${WORK_DIR}/static -G ${GENERATOR}
         -DERNEST_ODE_MODULE=${MODULE} -Dpkgcfg_lib_ODE_ode=${a})
endif()
