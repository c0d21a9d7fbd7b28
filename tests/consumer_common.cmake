# Shared by the install_consumer* ctest scripts: install this build tree into a prefix, configure
# the consumer project SOURCE_DIR against it (extra configure arguments: ARGN), build it.
function(run_step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "step failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
endfunction()

function(install_and_build_consumer)
  file(REMOVE_RECURSE ${WORK_DIR})
  run_step(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
  run_step(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR}
           -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release ${ARGN})
  run_step(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
endfunction()
