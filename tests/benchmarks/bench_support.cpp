#include "bench_support.h"

#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace solo::bench {
namespace {

// Collects the median aggregates while the console reporter prints as usual.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      const bool median = run.run_type == Run::RT_Aggregate && run.aggregate_name == "median";
      const bool single = run.run_type == Run::RT_Iteration && run.repetitions <= 1;
      if (median || single) medians_[run.run_name.str()] = run.GetAdjustedRealTime();
    }
  }
  void printRatios() const {
    // Family = text before the first '/'; its baseline = a member whose name has "baseline".
    std::map<std::string, double> baselines;
    for (const auto& [name, time] : medians_)
      if (name.find("baseline") != std::string::npos) baselines[name.substr(0, name.find('/'))] = time;
    if (baselines.empty()) return;
    std::printf("\nratio to the baseline of its family (median real time, same run):\n");
    for (const auto& [name, time] : medians_) {
      const auto base = baselines.find(name.substr(0, name.find('/')));
      if (base != baselines.end() && base->second > 0) std::printf("  %-60s %8.3fx\n", name.c_str(), time / base->second);
    }
  }

 private:
  std::map<std::string, double> medians_;
};

}  // namespace

int runWithRatios(int argc, char** argv) {
  std::vector<char*> args(argv, argv + argc);
  std::string repetitions = "--benchmark_repetitions=5";
  std::string aggregates = "--benchmark_report_aggregates_only=true";
  bool has_repetitions = false;
  for (int i = 1; i < argc; ++i) has_repetitions |= std::string(argv[i]).rfind("--benchmark_repetitions", 0) == 0;
  if (!has_repetitions) {
    args.push_back(repetitions.data());
    args.push_back(aggregates.data());
  }
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.printRatios();
  benchmark::Shutdown();
  return 0;
}

}  // namespace solo::bench
