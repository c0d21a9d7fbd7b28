# ODE for ernest (used by the build and by the installed ernestConfig.cmake).
#
# cpp/solver/ode_lcp.cpp defines ODE's internal constraint-solver entry, dxSolveLCP, and relies
# on the dynamic linker binding libode's own call to it (ARCHITECTURE.md, "The solver hook"). So
# ODE must be (1) a version whose dxSolveLCP has the signature and data layout ode_lcp.cpp reads:
# the 0.16 series (0.16.2, Debian 12, is the one tested; a run-time probe checks the layout
# again), and (2) a shared library: a static libode.a also defines dxSolveLCP, which does not
# link (two definitions) and could not be interposed anyway.
set(ERNEST_ODE_VERSION_MIN 0.16.0)   # first supported
set(ERNEST_ODE_VERSION_LESS 0.17)    # first not supported

# Fails the configuration unless `version` is in the supported range and no entry of `libraries`
# (pkg-config's resolved link libraries) is a static libode. Script-mode safe (tests/cmake).
function(ernest_check_ode version libraries)
  if(version VERSION_LESS ERNEST_ODE_VERSION_MIN OR
     NOT version VERSION_LESS ERNEST_ODE_VERSION_LESS)
    message(FATAL_ERROR
      "ernest: found ODE ${version}, supported ODE >= ${ERNEST_ODE_VERSION_MIN} and < "
      "${ERNEST_ODE_VERSION_LESS} (the 0.16 series; Debian 12 libode-dev 0.16.2 is tested). "
      "cpp/solver/ode_lcp.cpp replaces ODE's internal dxSolveLCP and reads ODE 0.16's data "
      "layout; install ODE 0.16.x, or point PKG_CONFIG_PATH at one.")
  endif()
  foreach(lib IN LISTS libraries)
    get_filename_component(name "${lib}" NAME)
    if(name MATCHES "^libode.*\\.a$")
      message(FATAL_ERROR
        "ernest: ODE resolves to the static library ${lib}; ernest needs the shared libode "
        "(libode.so). cpp/solver/ode_lcp.cpp defines ODE's dxSolveLCP so that the dynamic "
        "linker binds ODE's call to it: with a static libode the two definitions do not link. "
        "Install the shared library (Debian: libode-dev provides libode.so) or, for a self-built "
        "ODE, configure it with BUILD_SHARED_LIBS=ON.")
    endif()
  endforeach()
endfunction()

# pkg-config's `ode`, as the imported target PkgConfig::ODE, checked. A macro: the ODE_* results
# land in the caller's scope, as pkg_check_modules' do.
macro(ernest_find_ode)
  find_package(PkgConfig REQUIRED)
  pkg_check_modules(ODE REQUIRED IMPORTED_TARGET ode)
  ernest_check_ode("${ODE_VERSION}" "${ODE_LINK_LIBRARIES}")
endmacro()
