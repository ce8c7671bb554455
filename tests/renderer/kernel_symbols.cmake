# The per-instruction-set copies of the fast kernel must not define any symbol the linker
# could merge across them: an inline function emitted as a weak symbol by the AVX-512 copy
# may be the one kept for the scalar kernel, which then crashes on a CPU without AVX-512.
# Passes when every global symbol of each object is in its own namespace.
#   cmake -DNM=nm -DOBJECTS="a.o;b.o" -P kernel_symbols.cmake
foreach(obj ${OBJECTS})
  string(REGEX MATCH "tessera_kernel_([a-z0-9]+)" _ "${obj}")
  set(isa "${CMAKE_MATCH_1}")
  execute_process(COMMAND ${NM} -C --defined-only --extern-only ${obj} OUTPUT_VARIABLE syms RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0 OR isa STREQUAL "")
    message(FATAL_ERROR "cannot read the symbols of ${obj}")
  endif()
  string(REPLACE "\n" ";" lines "${syms}")
  set(own 0)
  foreach(line ${lines})
    if(line MATCHES "^[0-9a-f]+ [A-Za-z] (.*)$")
      set(name "${CMAKE_MATCH_1}")
      if(name MATCHES "^tessera::renderer::${isa}::")
        math(EXPR own "${own} + 1")
      elseif(NOT name MATCHES "^DW\\.ref\\.")  # the C++ personality routine's pointer: data
        message(SEND_ERROR "${isa} kernel defines '${name}' outside tessera::renderer::${isa}")
      endif()
    endif()
  endforeach()
  if(own EQUAL 0)
    message(FATAL_ERROR "${obj}: no symbol in tessera::renderer::${isa} (is this the kernel?)")
  endif()
  message(STATUS "${isa}: ${own} symbols, all in its namespace")
endforeach()
