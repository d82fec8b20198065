# Runs at install time (cmake --install, cpack): the hapfluid Python package for the system's
# python3, where Debian's python3 looks (<prefix>/lib/python3/dist-packages for /usr, the
# versioned dist-packages for another prefix), with its console commands in <prefix>/bin.
# pip builds it from a copy of the sources, so the checkout gets no build/ or egg-info of it.
# Inputs: HAPFLUID_SOURCE_DIR, HAPFLUID_BINARY_DIR, HAPFLUID_PIP_PYTHON (a python with pip and
# the build tools of scripts/constraints.txt: the project venv's).
if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  set(_site lib/python3/dist-packages)
else()
  execute_process(COMMAND /usr/bin/python3 -c "import sys; print('%d.%d' % sys.version_info[:2])"
                  OUTPUT_VARIABLE _version OUTPUT_STRIP_TRAILING_WHITESPACE COMMAND_ERROR_IS_FATAL ANY)
  set(_site lib/python${_version}/dist-packages)
endif()
set(_stage ${HAPFLUID_BINARY_DIR}/python-package)
file(REMOVE_RECURSE ${_stage})
file(COPY ${HAPFLUID_SOURCE_DIR}/scripts/pyproject.toml DESTINATION ${_stage}/src)
file(COPY ${HAPFLUID_SOURCE_DIR}/scripts/hapfluid DESTINATION ${_stage}/src
     PATTERN __pycache__ EXCLUDE PATTERN "*.pyc" EXCLUDE)
message(STATUS "Building the hapfluid Python package with ${HAPFLUID_PIP_PYTHON}")
execute_process(COMMAND ${CMAKE_COMMAND} -E env PIP_CONSTRAINT=${HAPFLUID_SOURCE_DIR}/scripts/constraints.txt
                        ${HAPFLUID_PIP_PYTHON} -m pip install --quiet --disable-pip-version-check --no-deps
                        --no-compile --target ${_stage}/target ${_stage}/src
                COMMAND_ERROR_IS_FATAL ANY)
file(REMOVE_RECURSE ${_stage}/src/build)
# Console commands: pip wrote them for the python that ran it; they run on the system's.
file(GLOB _commands ${_stage}/target/bin/*)
foreach(_command ${_commands})
  file(READ ${_command} _text)
  string(REGEX REPLACE "^#![^\n]*" "#!/usr/bin/python3" _text "${_text}")
  file(WRITE ${_command} "${_text}")
endforeach()
file(INSTALL ${_commands} DESTINATION ${CMAKE_INSTALL_PREFIX}/bin
     FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
# pip's record of where it built from names this build folder: no use on another machine.
file(REMOVE_RECURSE ${_stage}/target/bin ${_stage}/target/hapfluid-${HAPFLUID_VERSION}.dist-info/direct_url.json)
file(INSTALL ${_stage}/target/ DESTINATION ${CMAKE_INSTALL_PREFIX}/${_site})
