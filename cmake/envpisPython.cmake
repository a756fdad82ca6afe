# SPDX-License-Identifier: Apache-2.0
# Finds what the Python bindings need: a Python 3 interpreter that imports numpy, its development
# headers, and pybind11's CMake package. Sets ENVPIS_PYTHON_FOUND, and ENVPIS_PYTHON_MISSING to a
# one-line reason when something is missing.
#
# The interpreter: Python3_EXECUTABLE if the user set it, else the first of `python3` on PATH and
# /usr/bin/python3 that imports numpy. Why not FindPython3's own choice: on machines with pyenv (or a
# virtualenv) on PATH it picks a Python without Debian's numpy and pytest, and the module and its tests
# would then be built for an interpreter that cannot use them.

function(envpis_python_imports_numpy exe result)
  execute_process(COMMAND "${exe}" -c "import numpy" RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
  if(rc EQUAL 0)
    set(${result} TRUE PARENT_SCOPE)
  else()
    set(${result} FALSE PARENT_SCOPE)
  endif()
endfunction()

set(ENVPIS_PYTHON_FOUND FALSE)
set(ENVPIS_PYTHON_MISSING "")
if(NOT Python3_EXECUTABLE)
  find_program(envpis_path_python3 NAMES python3 NO_CACHE)
  foreach(candidate IN ITEMS "${envpis_path_python3}" /usr/bin/python3)
    if(candidate AND EXISTS "${candidate}")
      envpis_python_imports_numpy("${candidate}" ok)
      if(ok)
        set(Python3_EXECUTABLE "${candidate}" CACHE FILEPATH "Python 3 the bindings are built for")
        break()
      endif()
    endif()
  endforeach()
endif()

if(NOT Python3_EXECUTABLE)
  set(ENVPIS_PYTHON_MISSING "no python3 that imports numpy (apt-get install python3-numpy)")
  return()
endif()
find_package(Python3 3.7 QUIET COMPONENTS Interpreter Development.Module)
if(NOT Python3_Development.Module_FOUND)
  set(ENVPIS_PYTHON_MISSING "no Python development headers for ${Python3_EXECUTABLE} (apt-get install python3-dev)")
  return()
endif()
find_package(pybind11 2.6 CONFIG QUIET)
if(NOT pybind11_FOUND)
  set(ENVPIS_PYTHON_MISSING "pybind11 not found (apt-get install pybind11-dev)")
  return()
endif()
set(ENVPIS_PYTHON_FOUND TRUE)
