// Marking by an indicator (indicator.hpp). O(cells log cells) at most: one
// sort of the candidate ids by value for Top and Dorfler.
#include "bisect/indicator.hpp"

#include "core/names.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace bisect {
namespace {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// Cell ids by decreasing value, ties to the lower id.
std::vector<CellId> by_value(const std::vector<double> &values) {
  std::vector<CellId> ids(values.size());
  std::iota(ids.begin(), ids.end(), CellId(0));
  std::sort(ids.begin(), ids.end(), [&](CellId a, CellId b) {
    return values[a] > values[b] || (values[a] == values[b] && a < b);
  });
  return ids;
}

} // namespace

std::vector<CellId> mark_by_indicator(const std::vector<double> &values, IndicatorRule rule,
                                      double parameter, const std::string &file, const Mesh *mesh) {
  std::vector<CellId> out;
  switch (rule) {
  case IndicatorRule::Above:
  case IndicatorRule::Below:
    if (!std::isfinite(parameter))
      throw UsageError("the threshold must be a finite number");
    for (std::size_t c = 0; c < values.size(); ++c)
      if (rule == IndicatorRule::Above ? values[c] > parameter : values[c] < parameter)
        out.push_back(CellId(c));
    return out;
  case IndicatorRule::Top: {
    if (!(parameter > 0 && parameter <= 1))
      throw UsageError("--top takes a fraction F with 0 < F <= 1, not " + number(parameter));
    const std::size_t k =
        std::min(values.size(), std::size_t(std::ceil(parameter * double(values.size()))));
    std::vector<CellId> ids = by_value(values);
    out.assign(ids.begin(), ids.begin() + std::ptrdiff_t(k));
    break;
  }
  case IndicatorRule::Dorfler: {
    if (!(parameter > 0 && parameter <= 1))
      throw UsageError("--dorfler takes theta with 0 < theta <= 1, not " + number(parameter));
    double total = 0;
    for (std::size_t c = 0; c < values.size(); ++c) {
      if (values[c] < 0)
        throw InputError(file, (mesh ? cell_name(*mesh, CellId(c)) : "cell " + std::to_string(c)) +
                                   ": indicator value " + number(values[c]) +
                                   " is negative (Dorfler marking sums squares of values >= 0)");
      total += values[c] * values[c];
    }
    if (total == 0)
      return out; // nothing to refine
    std::vector<CellId> ids = by_value(values);
    double sum = 0;
    const double goal = parameter * total;
    for (CellId c : ids) {
      if (sum >= goal)
        break;
      out.push_back(c);
      sum += values[c] * values[c];
    }
    break;
  }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<double> cell_indicator(const Mesh &mesh, const std::string &name,
                                   const std::string &file) {
  auto find = [&](const std::vector<DataArray> &arrays) -> const DataArray * {
    for (const DataArray &a : arrays)
      if (a.name == name)
        return &a;
    return nullptr;
  };
  const DataArray *cell = find(mesh.cell_data), *point = cell ? nullptr : find(mesh.point_data);
  if (!cell && !point) {
    std::string have;
    for (const DataArray &a : mesh.cell_data)
      have += (have.empty() ? "" : ", ") + ("cell array '" + a.name + "'");
    for (const DataArray &a : mesh.point_data)
      have += (have.empty() ? "" : ", ") + ("point array '" + a.name + "'");
    throw InputError(file, "no cell or point array '" + name +
                               "' for the indicator (the file has " +
                               (have.empty() ? std::string("no arrays") : have) + ")");
  }
  const DataArray &a = cell ? *cell : *point;
  if (a.components != 1)
    throw InputError(file, std::string(cell ? "cell" : "point") + " array '" + name + "' has " +
                               std::to_string(a.components) +
                               " components; an indicator has one value per cell or vertex");
  for (std::size_t i = 0; i < a.values.size(); ++i)
    if (!std::isfinite(a.values[i]))
      throw InputError(file, (cell ? cell_name(mesh, CellId(i)) : vertex_name(mesh, VertexId(i))) +
                                 ": indicator '" + name + "' is " + number(a.values[i]));
  if (cell)
    return a.values;
  std::vector<double> out(mesh.num_cells());
  const int n = mesh.cell_size();
  for (std::size_t c = 0; c < out.size(); ++c) {
    const VertexId *x = mesh.cell(CellId(c));
    double v = a.values[x[0]];
    for (int i = 1; i < n; ++i)
      v = std::max(v, a.values[x[i]]);
    out[c] = v;
  }
  return out;
}

} // namespace bisect
