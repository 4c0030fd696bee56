# add_browser_test(NAME [MIN_SVG N] COMMANDS CMD...)
# A CTest (label `browser`) that runs the bash commands CMD... in a fresh directory
# (build/browser/NAME; $ROTACAL is the rotacal binary, $SRC the source tree), then opens every
# .html they wrote in headless Chromium and checks it rendered (scripts/browser_check.sh): no
# script error, at least N <svg> elements (default 1), a screenshot that is not blank. A new
# cycle's report test is one call, e.g.
#   add_browser_test(report_rtest MIN_SVG 4 COMMANDS
#     "$ROTACAL plan --cycle rtest --machine $SRC/examples/machines/bc_trunnion.json -o plan.json" ...)
find_package(PNG REQUIRED)
add_executable(png_stats ${PROJECT_SOURCE_DIR}/tests/report/png_stats.cpp)
target_link_libraries(png_stats PRIVATE PNG::PNG)
rotacal_warnings(png_stats)

function(add_browser_test name)
  cmake_parse_arguments(B "" "MIN_SVG" "COMMANDS" ${ARGN})
  if(NOT B_MIN_SVG)
    set(B_MIN_SVG 1)
  endif()
  add_test(NAME ${name}
           COMMAND bash ${PROJECT_SOURCE_DIR}/scripts/browser_test.sh $<TARGET_FILE:rotacal> $<TARGET_FILE:png_stats>
                   ${PROJECT_BINARY_DIR}/browser/${name} ${B_MIN_SVG} ${B_COMMANDS})
  # 15 s at most measured under load (docs/build-profile.md)
  set_tests_properties(${name} PROPERTIES LABELS browser TIMEOUT 120)
endfunction()
