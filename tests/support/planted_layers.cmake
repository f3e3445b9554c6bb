# A tree whose model layer includes a solver header: check_layers.py must exit 1 naming it.
file(REMOVE_RECURSE ${WORK})
file(WRITE ${WORK}/src/solver/step.hpp "#pragma once\n")
file(WRITE ${WORK}/src/model/model.cpp "#include \"solver/step.hpp\"\n")
execute_process(COMMAND ${PYTHON} ${SCRIPT} ${WORK} RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(NOT rc EQUAL 1 OR NOT out MATCHES "src/model/model.cpp:1: the model layer includes")
  message(FATAL_ERROR "check_layers.py accepted an include up the stack (exit ${rc}): ${out}")
endif()
