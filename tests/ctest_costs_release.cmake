# ctest starts the longest tests first when it has no timings of its own (a clean clone, as in CI): seconds each took
# in a clean-clone .ci/run of 54ba2f5 on the 2-core CI-like machine (release build). Only the order of tests depends on them;
# a name no longer in the suite is ignored. Regenerate from build/release/Testing/Temporary/CTestCostData.txt.
set_tests_properties(OpenClParity.ThePublicStepsGiveTheCpuAnswersAtBothThicknesses PROPERTIES COST 54)
set_tests_properties(OpenClParity.TheDefaultSuiteGivesTheCpuAnswersAtBothThicknesses PROPERTIES COST 18)
set_tests_properties(OpenClParity.ApccdKnobsGiveTheCpuAnswers PROPERTIES COST 15)
set_tests_properties(Mpi.TwoRanksGiveEveryVerdictAndCountOfOne PROPERTIES COST 9)
set_tests_properties(ReferenceSharedData.StepTruthHoldsEverySampleColliding PROPERTIES COST 9)
set_tests_properties(FullAnswers.ThePublicStepsGiveTheRecordedAnswers PROPERTIES COST 9)
set_tests_properties(Cli.StressPrintsFamiliesAndWritesTheSuiteAsQueries PROPERTIES COST 9)
set_tests_properties(Conservative.NoMissOnTheWholeExtremesSuite PROPERTIES COST 6)
set_tests_properties(Mpi.ARerunOnOneProcessCompletesWhatADeadRankZeroLeft PROPERTIES COST 5)
set_tests_properties(Mpi.ARerunCompletesWhatADeadWorkerRankLeft PROPERTIES COST 4)
