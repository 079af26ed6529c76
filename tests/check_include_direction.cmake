# Fails when a file of one module includes a header of a module it may not depend on (compiles
# nothing). Run as: cmake -DSOURCE_DIR=<repo> -P tests/check_include_direction.cmake
# Scans include/texgrad/<m>/, src/<m>/ and tests/<m>/ (cli/ and tests/cli/ as module cli,
# python/src and python/bench as module python) for
# #include "texgrad/<other>/..." and #include "<other>/..." (a module's private src/ headers).
cmake_minimum_required(VERSION 3.22)
if(NOT SOURCE_DIR)
  message(FATAL_ERROR "pass -DSOURCE_DIR=<texgrad source tree>")
endif()

# The allowed direct dependencies (docs/architecture.md); a module may include its own headers
# and those of every module it reaches through these arrows.
set(modules core io lattice atlas fem operators solver apps viewer cli python)
set(deps_core "")
set(deps_io core)
set(deps_lattice core)
set(deps_atlas io lattice)
set(deps_fem atlas)
set(deps_operators fem)
set(deps_solver lattice core)
set(deps_apps operators solver)
set(deps_viewer apps)
set(deps_cli viewer apps)
set(deps_python apps)  # the Python module (python/src, python/bench): a front end beside cli

# Transitive closure, in the order above (every module's dependencies come before it).
foreach(m IN LISTS modules)
  set(reach_${m} ${m})
  foreach(d IN LISTS deps_${m})
    list(APPEND reach_${m} ${reach_${d}})
  endforeach()
  list(REMOVE_DUPLICATES reach_${m})
endforeach()

set(violations "")
# A folder under include/texgrad/ or src/ that is no module in the graph must be added to it.
foreach(root include/texgrad src)
  file(GLOB entries LIST_DIRECTORIES true RELATIVE "${SOURCE_DIR}/${root}" "${SOURCE_DIR}/${root}/*")
  foreach(entry IN LISTS entries)
    if(IS_DIRECTORY "${SOURCE_DIR}/${root}/${entry}" AND NOT entry IN_LIST modules)
      list(APPEND violations "${root}/${entry}/ is not a module of the dependency graph")
    endif()
  endforeach()
endforeach()

set(checked 0)
foreach(m IN LISTS modules)
  set(dirs include/texgrad/${m} src/${m} tests/${m})
  if(m STREQUAL "cli")
    list(APPEND dirs cli)
  elseif(m STREQUAL "python")
    list(APPEND dirs python/src python/bench)
  endif()
  foreach(dir IN LISTS dirs)
    file(GLOB_RECURSE files "${SOURCE_DIR}/${dir}/*.h" "${SOURCE_DIR}/${dir}/*.cpp"
         "${SOURCE_DIR}/${dir}/*.inl")
    foreach(file IN LISTS files)
      math(EXPR checked "${checked} + 1")
      file(STRINGS "${file}" lines REGEX "^[ \t]*#[ \t]*include[ \t]*[\"<]")
      foreach(line IN LISTS lines)
        if(line MATCHES "include[ \t]*[\"<](texgrad/)?([a-z_]+)/")
          set(target "${CMAKE_MATCH_2}")
          if(target IN_LIST modules AND NOT target IN_LIST reach_${m})
            file(RELATIVE_PATH rel "${SOURCE_DIR}" "${file}")
            string(STRIP "${line}" line)
            list(JOIN reach_${m} ", " allowed)
            list(APPEND violations "${rel}: ${line}: module ${m} may include only ${allowed}")
          endif()
        endif()
      endforeach()
    endforeach()
  endforeach()
endforeach()

if(checked EQUAL 0)
  message(FATAL_ERROR "no source files found under ${SOURCE_DIR}")
endif()
if(violations)
  list(JOIN violations "\n  " text)
  message(FATAL_ERROR "include direction violated:\n  ${text}")
endif()
message(STATUS "include direction: ${checked} files follow the module graph")
