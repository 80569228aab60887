# mebake_module(NAME SOURCES ... [DEPS ...] [PRIVATE_DEPS ...])
# Makes the static library mebake_NAME. Its headers are reachable as "NAME/x.h" only
# through an include root private to this module (a symlink in the build tree), so a
# module that does not link NAME cannot include its headers: layering is enforced.
function(mebake_module name)
  cmake_parse_arguments(M "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  set(inc ${CMAKE_BINARY_DIR}/include/${name})
  file(MAKE_DIRECTORY ${inc})
  if(NOT EXISTS ${inc}/${name})
    file(CREATE_LINK ${CMAKE_CURRENT_SOURCE_DIR} ${inc}/${name} SYMBOLIC)
  endif()
  if(NOT M_SOURCES)  # a module that has no code yet still links
    set(M_SOURCES ${CMAKE_BINARY_DIR}/empty_${name}.cpp)
    file(WRITE ${M_SOURCES} "// ${name} has no sources yet\n")
  endif()
  add_library(mebake_${name} STATIC ${M_SOURCES})
  target_include_directories(mebake_${name} PUBLIC ${inc})
  target_link_libraries(mebake_${name} PUBLIC ${M_DEPS} PRIVATE ${M_PRIVATE_DEPS})
endfunction()

# mebake_test(NAME SOURCES ... LIBS ... [LABELS ...]): one GoogleTest executable, its
# tests registered one by one with ctest.
function(mebake_test name)
  cmake_parse_arguments(T "" "" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${T_SOURCES})
  target_link_libraries(${name} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main)
  # Helpers shared by several test folders live in tests/support/ ("support/x.h").
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_compile_definitions(${name} PRIVATE
    MEBAKE_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    MEBAKE_SHARED_DATA="${PROJECT_SOURCE_DIR}/../shared/data"
    MEBAKE_BINARY="$<TARGET_FILE:mebake>"
    MEBAKE_MKSCAN="$<TARGET_FILE:mkscan>")
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${T_LABELS}")
endfunction()
