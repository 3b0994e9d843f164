# cmake -DOUTPUT=FILE -P run_to_file.cmake -- PROGRAM ARGS...: runs PROGRAM ARGS with its standard
# output in FILE, failing the build when it fails (the completion scripts and man pages of
# cli/CMakeLists.txt, written by the built `fivebar help`).
set(_args)
set(_seen FALSE)
foreach(_i RANGE ${CMAKE_ARGC})
  if(_seen)
    list(APPEND _args "${CMAKE_ARGV${_i}}")
  elseif("${CMAKE_ARGV${_i}}" STREQUAL "--")
    set(_seen TRUE)
  endif()
endforeach()
list(POP_BACK _args)  # CMAKE_ARGV<CMAKE_ARGC> is past the end
execute_process(COMMAND ${_args} OUTPUT_FILE "${OUTPUT}.tmp" RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  file(REMOVE "${OUTPUT}.tmp")
  message(FATAL_ERROR "${_args}: exit ${_rc}")
endif()
file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")
