// The C++ side of python/bench/bench_filter.py: times filterTexture on a prepared TexelDomain and
// measures the memory the call adds, the same way the script measures texgrad.filter.
//   texgrad_filter_call MESH TEXTURE REPETITIONS  ->  one JSON line on stdout
#include <sys/resource.h>

#include <chrono>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "texgrad/apps/filter.h"
#include "texgrad/io/image_io.h"
#include "texgrad/io/mesh_reader.h"

namespace {

/// The number a field of /proc/self/status holds ("VmRSS" in kB, "Threads"), or -1.
double statusValue(const std::string& field) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind(field + ":", 0) == 0) return std::stod(line.substr(field.size() + 1));
  return -1.0;
}

/// A field of /proc/self/status ("VmRSS", "VmHWM") in MB.
double statusMegabytes(const std::string& field) {
  return statusValue(field) / 1024.0;
}

/// CPU seconds of the process so far (all threads, user + system).
double cpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
  };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

/// Resets the peak resident size (VmHWM) to the current one (Linux clear_refs, value 5).
void resetPeak() {
  std::ofstream("/proc/self/clear_refs") << "5";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: texgrad_filter_call MESH TEXTURE REPETITIONS\n";
    return 2;
  }
  const texgrad::Image texture = texgrad::readImage(argv[2]);
  const texgrad::TexelDomain domain(texgrad::readMesh(argv[1]), texture.width, texture.height,
                                    texgrad::OperatorOptions::assembledOnce());
  const texgrad::FilterOptions options;  // the defaults texgrad.filter uses
  std::vector<double> seconds, cpu;
  double before = 0.0, peak = 0.0;
  for (int k = 0; k < std::stoi(argv[3]); ++k) {
    before = statusMegabytes("VmRSS");
    resetPeak();
    const double cpuStart = cpuSeconds();
    const auto start = std::chrono::steady_clock::now();
    const texgrad::FilterResult result = texgrad::filterTexture(domain, texture, options);
    seconds.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    cpu.push_back(cpuSeconds() - cpuStart);
    peak = statusMegabytes("VmHWM");
  }
  std::cout << "{\"seconds\": [";
  for (size_t k = 0; k < seconds.size(); ++k) std::cout << (k ? ", " : "") << seconds[k];
  std::cout << "], \"cpu_seconds\": [";
  for (size_t k = 0; k < cpu.size(); ++k) std::cout << (k ? ", " : "") << cpu[k];
  std::cout << "], \"rss_before_mb\": " << before << ", \"peak_mb\": " << peak
            << ", \"unknowns\": " << domain.unknowns()
            << ", \"threads\": " << statusValue("Threads") << "}\n";
  return 0;
}
