# texgrad_module(NAME [FRONT_END] [DEPENDS targets...] [PRIVATE_LIBS targets...]
#                [HEADER_ONLY targets...])
# Defines the library texgrad_NAME (alias texgrad::NAME) from src/NAME/*.cpp, with the public
# headers of include/texgrad/NAME/, and records NAME in the global property TEXGRAD_MODULES (and
# TEXGRAD_LIBRARY_MODULES unless FRONT_END), which texgrad::texgrad, the install rules and
# texgrad.pc read. DEPENDS are linked publicly; PRIVATE_LIBS privately (a static library's
# consumers link them too: the CMake package finds them); HEADER_ONLY libraries are used by the
# sources only, so a consumer never needs them.
function(texgrad_module name)
  cmake_parse_arguments(ARG "FRONT_END" "" "DEPENDS;PRIVATE_LIBS;HEADER_ONLY" ${ARGN})
  set(target texgrad_${name})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/${name}/*.cpp)
  set(includes $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include>
               $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  if(sources)
    add_library(${target} ${sources})  # static, or shared with BUILD_SHARED_LIBS=ON
    # Position-independent so that the static libraries can go into a shared library or a Python
    # extension; $ORIGIN lets the installed shared libraries find each other. No <target>_EXPORTS
    # define (nothing uses it): static and shared objects then compile alike (one ccache entry).
    set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON DEFINE_SYMBOL ""
      VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR}
      INSTALL_RPATH "$ORIGIN")
    target_compile_features(${target} PUBLIC cxx_std_20)
    target_include_directories(${target} PUBLIC ${includes} PRIVATE ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(${target} PUBLIC Eigen3::Eigen ${ARG_DEPENDS}
                          PRIVATE $<BUILD_INTERFACE:texgrad_warnings> ${ARG_PRIVATE_LIBS})
    foreach(lib IN LISTS ARG_HEADER_ONLY)
      target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:${lib}>)
    endforeach()
    if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
      # -fPIC alone lets GCC assume any exported function may be replaced at load time, which
      # stops inlining across them; texgrad's functions are never interposed.
      target_compile_options(${target} PRIVATE -fno-semantic-interposition)
    endif()
  else()
    add_library(${target} INTERFACE)
    target_compile_features(${target} INTERFACE cxx_std_20)
    target_include_directories(${target} INTERFACE ${includes})
    target_link_libraries(${target} INTERFACE Eigen3::Eigen ${ARG_DEPENDS})
  endif()
  add_library(texgrad::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  set_property(GLOBAL APPEND PROPERTY TEXGRAD_MODULES ${name})
  if(NOT ARG_FRONT_END)
    set_property(GLOBAL APPEND PROPERTY TEXGRAD_LIBRARY_MODULES ${name})
  endif()
endfunction()
