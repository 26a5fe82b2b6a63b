# The `library_consumer` test: install the freshly built Tessera into a scratch prefix, configure and
# build tests/consumer against it with find_package(Tessera), and run it.
# It also validates on the lattice and hairball of the pathology battery, written by PATHOLOGY_WRITER.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DSCENE=... -DPATHOLOGY_WRITER=... -P run_consumer.cmake
foreach(var BUILD_DIR SOURCE_DIR WORK_DIR SCENE PATHOLOGY_WRITER)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_consumer.cmake: ${var} not set")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK_DIR})
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  message(STATUS "${what}: ok")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()
run("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
if(NOT EXISTS ${WORK_DIR}/prefix/include/tessera/tessera.h)
  message(FATAL_ERROR "the install has no include/tessera/tessera.h")
endif()
# A sanitizer build of the library needs the same sanitizers in the program that loads it (the
# ASan runtime must be the first library loaded).
set(san_flags "")
if(SANITIZE)
  set(san_flags -DCMAKE_CXX_FLAGS=-fsanitize=${SANITIZE} -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=${SANITIZE})
endif()
run("configure consumer" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/consumer -B ${WORK_DIR}/build
    -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release ${san_flags})
run("build consumer" ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
file(MAKE_DIRECTORY ${WORK_DIR}/meshes)
run("write pathology meshes" ${PATHOLOGY_WRITER} ${WORK_DIR}/meshes)
run("run consumer" ${WORK_DIR}/build/consumer ${SCENE}
    ${WORK_DIR}/meshes/integer-lattice.obj ${WORK_DIR}/meshes/sliver-hairball.obj)
message("${last_output}")
