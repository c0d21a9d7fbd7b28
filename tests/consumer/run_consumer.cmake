# Driven by ctest (install_consumer): install, configure the consumer, build it, run it.
include(${CMAKE_CURRENT_LIST_DIR}/../consumer_common.cmake)
install_and_build_consumer()
run_step(${WORK_DIR}/build/ernest_consumer)
