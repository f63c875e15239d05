#include "run_helpers.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

namespace spate::test {

std::vector<std::pair<double, double>> read_probe(const std::filesystem::path& csv, int col) {
  std::ifstream in(csv);
  std::vector<std::pair<double, double>> out;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::stringstream s(line);
    std::vector<double> v;
    for (std::string cell; std::getline(s, cell, ',');) v.push_back(std::stod(cell));
    if (static_cast<int>(v.size()) > col) out.emplace_back(v[0], v[col]);
  }
  return out;
}

double mean_after(const std::filesystem::path& csv, int col, double from) {
  double sum = 0.0;
  int n = 0;
  for (auto [t, v] : read_probe(csv, col))
    if (t > from) sum += v, ++n;
  return n ? sum / n : NAN;
}

}  // namespace spate::test
