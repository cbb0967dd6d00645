# cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DCXX_COMPILER=... [-DCXX_FLAGS=... -DEXE_LINKER_FLAGS=...]
#       [-DPYTHON_DIR=lib/python3.X/dist-packages] -P tests/install_consumer.cmake
# (No ';' in the commands given to run(): ARGN would split them.)
# Installs the build into WORK_DIR/prefix, builds tests/consumer against the installed package
# (find_package(unjam), unjam::core) and runs it on a fixture packing; with PYTHON_DIR, imports
# the installed Python module from there.
foreach(var BUILD_DIR SOURCE_DIR WORK_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "${var} is not set")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK_DIR})
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/consumer -B ${WORK_DIR}/build -G Ninja
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix
    "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${EXE_LINKER_FLAGS}"
    "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}")
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/consumer ${SOURCE_DIR}/tests/fixtures/p50-mu0.1)
# phi and z of the fixture as `unjam info` prints them.
if(NOT out MATCHES "N 50 phi 0\\.829153 z 3\\.")
  message(FATAL_ERROR "unexpected output of the consumer: ${out}")
endif()
message("consumer: ${out}")
run(${WORK_DIR}/prefix/bin/unjam --version)
message("installed tool: ${out}")
if(PYTHON_DIR)
  run(${CMAKE_COMMAND} -E env PYTHONPATH=${WORK_DIR}/prefix/${PYTHON_DIR} /usr/bin/python3 -c
      "import unjam\np = unjam.read_packing('${SOURCE_DIR}/tests/fixtures/p50-mu0.1')\nprint(unjam.__file__, p.N)")
  if(NOT out MATCHES "^${WORK_DIR}/prefix/${PYTHON_DIR}/unjam.*\\.so 50\n$")
    message(FATAL_ERROR "unexpected output of the installed Python module: ${out}")
  endif()
  message("installed module: ${out}")
endif()
