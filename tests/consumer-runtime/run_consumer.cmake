# Driven by ctest (install_consumer_runtime): install the build tree, configure the onboard app
# against the installed ernest (component runtime) and the torch wheel's libtorch, build, run.
include(${CMAKE_CURRENT_LIST_DIR}/../consumer_common.cmake)
install_and_build_consumer(-DTorch_DIR=${TORCH_DIR})
run_step(${WORK_DIR}/build/onboard_app ${WORK_DIR}/onboard_policy.pt)
# The installed sim-in-the-loop executable runs from the install tree (RPATH to torch/lib).
run_step(${WORK_DIR}/prefix/bin/ernest_runtime --policy ${WORK_DIR}/onboard_policy.pt --scenario flat
         --seed 1 --duration 2 --quiet)
