# Runs each of CMD1 (1D) and CMD2 (2D) into a fresh folder and reads their XDMF back with meshio
# (tests/io/check_xdmf.py): ParaView and VisIt open a run directly.
file(REMOVE_RECURSE ${OUT})
foreach(i 1 2)
  execute_process(COMMAND ${CMD${i}} --quiet --out ${OUT}/run${i} RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "run ${i} failed (${rc}): ${err}")
  endif()
endforeach()
execute_process(COMMAND /usr/bin/python3 ${SCRIPT} ${OUT}/run1 ${OUT}/run2 RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${out}\n${err}")
endif()
message(STATUS "${out}")
