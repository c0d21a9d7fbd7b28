# Driven by ctest (install_consumer_runtime): install the build tree, configure the onboard app
# against the installed ernest (component runtime) and the torch wheel's libtorch, build, run.
function(run_step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "step failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
run_step(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
run_step(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
         -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DTorch_DIR=${TORCH_DIR} -DCMAKE_BUILD_TYPE=Release)
run_step(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run_step(${WORK_DIR}/build/onboard_app ${WORK_DIR}/onboard_policy.pt)
# The installed sim-in-the-loop executable runs from the install tree (RPATH to torch/lib).
run_step(${WORK_DIR}/prefix/bin/ernest_runtime --policy ${WORK_DIR}/onboard_policy.pt --scenario flat
         --seed 1 --duration 2 --quiet)
