# Compiles SOURCE (syntax only) and passes when it fails with a message matching EXPECT: a policy that
# misses its concept must fail with a sentence that says what is missing.
execute_process(COMMAND ${CXX} -std=c++20 -fsyntax-only ${INCLUDES} ${SOURCE} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(rc EQUAL 0)
  message(FATAL_ERROR "${SOURCE} compiled, but should not have")
endif()
if(NOT err MATCHES "${EXPECT}")
  message(FATAL_ERROR "${SOURCE} failed without the expected sentence '${EXPECT}':\n${err}")
endif()
