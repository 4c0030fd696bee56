# The tiers' timeouts, and which GoogleTest cases are statistical (tests/CMakeLists.txt). Read at
# configure time (the timeouts) and by CTest (rotacal_apply_tiers, from each test directory's
# rotacal_tiers.cmake), so only commands that both know.
#
# Timeouts: the slowest test of the tier measured with `ctest -L TIER -j2` on the 2-core machine
# under three concurrent builds (docs/build-profile.md), times 2.5 to 6, so that a hang fails in
# minutes, not after 600 s, while a loaded machine still passes: unit 24 s, integration 65 s
# (RtestCli.ThermalSeriesEndToEnd; the bad-input corpus has its own), statistical 31 s. In CI's
# whole-suite run (`ctest -j6` beside the niced sanitizer and LTO builds) the slowest unit test
# took 40 s (RtestTiltBudget.SensorGainsMatchTheReadingsScaledDirectly, 5.6 s of CPU alone), so
# unit's limit is 120 s; integration's slowest there 127 s, statistical's 85 s. Since every cycle's
# rates are tested on machines drawn from their contributors, statistical's slowest in that run is
# 162 s (SpaceframeRealMachine.JudgeScreenAndBudgetKeepTheirRatesOnDrawnMachines, 36 s alone) and
# integration's 145 s (RtestCli.ThermalSeriesEndToEnd, 30 s alone): statistical 420 s, integration
# 420 s, 2.5 x and 2.9 x.
set(ROTACAL_TIMEOUT_unit 120)
set(ROTACAL_TIMEOUT_integration 420)
set(ROTACAL_TIMEOUT_statistical 420)

# Statistical: a rate over many seeds (false alarms within alpha, detection power, coverage of the
# expanded uncertainty, a Monte Carlo against the closed form): regular expressions on the test
# names, as CTest lists them.
set(ROTACAL_STATISTICAL_TESTS
  # false alarms on clean seeds
  "FalseAlarm" "AlphaShareOfAlarms" "CleanSeedsRaise" "CleanRunsRarely"
  # power: a hidden effect found in most seeds
  "HiddenDriftFound" "HiddenScaleFound" "HiddenHarmonicFound" "HiddenGlitchFound" "IsFoundWithItsParametersWithin3u"
  # coverage: the truth within the reported uncertainty as often as claimed
  "AsOftenAsClaimed" "Over200Seeds" "WithinReportedUncertainty" "WithinTheReportedUncertainty"
  "WithNoiseWithinUncertainty" "NoisyLocationErrorsWithinTheirUncertainty"
  # a Monte Carlo, or drawn values, against the closed form
  "MonteCarlo" "RefitsOfDrawnContributors" "HasTheRequestedSpread" "HaveTheStatedSpread"
  "SensorResponseMatchesTheSimulatorsOwn" "CentreNullDrawsHaveThe"
  # a rate of the screen over seeds: a gross error of its stated reach caught as often as claimed
  "CaughtEightTimesInTen"
  # machines drawn from their declared contributors: the screen's and the judge's rates on them
  "RealMachine\\." "KeepsItsRateOn" "KeepTheirRates" "StandardNormalUnderTheDeclaration"
  "TheJudgeWhitensByTheFullCovariance"
)

# rotacal_apply_tiers(LIST TIER ...): each test named in the variable LIST gets label statistical
# and its timeout if it matches ROTACAL_STATISTICAL_TESTS, else TIER and TIER's timeout.
function(rotacal_apply_tiers)
  set(args ${ARGN})
  while(args)
    list(POP_FRONT args list tier)
    foreach(t IN LISTS ${list})
      set(label ${tier})
      foreach(re ${ROTACAL_STATISTICAL_TESTS})
        if(t MATCHES "${re}")
          set(label statistical)
          break()
        endif()
      endforeach()
      set_tests_properties("${t}" PROPERTIES LABELS ${label} TIMEOUT ${ROTACAL_TIMEOUT_${label}})
    endforeach()
  endwhile()
endfunction()
