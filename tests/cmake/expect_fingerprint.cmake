# Runs CMD into OUT on one thread and checks its last snapshot against the fingerprint FILE
# (scripts/fingerprint.py): a change that keeps the physics keeps every dataset to the bit.
file(REMOVE_RECURSE ${OUT})
execute_process(COMMAND ${CMD} --out ${OUT} --threads 1 --quiet RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "run failed (${rc}):\n${out}\n${err}")
endif()
execute_process(COMMAND /usr/bin/python3 ${SCRIPT} ${OUT} --check ${FILE} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${out}\n${err}")
endif()
message(STATUS "${out}")
