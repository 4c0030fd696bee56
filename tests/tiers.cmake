# The tiers' timeouts, and which GoogleTest cases are statistical (tests/CMakeLists.txt). Read at
# configure time (the timeouts) and by CTest (rotacal_apply_tiers, from each test directory's
# rotacal_tiers.cmake), so only commands that both know.
#
# Timeouts: about five times the slowest test of the tier measured on the 2-core machine with
# `ctest -j2` (docs/build-profile.md), so that a hang fails in minutes, not after 600 s, while a
# loaded machine still passes.
set(ROTACAL_TIMEOUT_unit 60)
set(ROTACAL_TIMEOUT_integration 300)
set(ROTACAL_TIMEOUT_statistical 600)

# Statistical: a rate over many seeds (false alarms within alpha, detection power, coverage of the
# expanded uncertainty, a Monte Carlo against the closed form). Full test names, as CTest lists them.
set(ROTACAL_STATISTICAL_TESTS
  "^Judge\\.CleanSeedsFalseAlarmsWithinAlpha$"
)

function(rotacal_apply_tiers)
  foreach(list ${ARGN})
    foreach(t IN LISTS ${list})
      foreach(re ${ROTACAL_STATISTICAL_TESTS})
        if(t MATCHES "${re}")
          set_tests_properties("${t}" PROPERTIES LABELS statistical TIMEOUT ${ROTACAL_TIMEOUT_statistical})
          break()
        endif()
      endforeach()
    endforeach()
  endforeach()
endfunction()
