#include "worker/mapping/filter_chain.h"

#include <cmath>
#include <set>
#include <stdexcept>

namespace keel::mapping {
namespace {

using nlohmann::json;

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

double number_field(const json& object, const std::string& key, double fallback,
                    const std::string& where, bool positive) {
  if (!object.contains(key)) return fallback;
  const json& value = object.at(key);
  if (!value.is_number()) fail(where + "." + key, "expected a number, got " + value.dump());
  const double number = value.get<double>();
  if (!std::isfinite(number) || (positive && number <= 0.0) || (!positive && number < 0.0)) {
    fail(where + "." + key, std::string("expected a ") + (positive ? "positive" : "non-negative") +
                                " number, got " + value.dump());
  }
  return number;
}

int count_field(const json& object, const std::string& key, int fallback,
                const std::string& where) {
  if (!object.contains(key)) return fallback;
  const json& value = object.at(key);
  if (!value.is_number_integer() || value.get<long long>() < 0 ||
      value.get<long long>() > 1000000) {
    fail(where + "." + key, "expected a whole number in [0, 1000000], got " + value.dump());
  }
  return value.get<int>();
}

Eigen::Vector3d vector_field(const json& object, const std::string& key, const std::string& where) {
  if (!object.contains(key)) fail(where + "." + key, "missing (expected [x, y, z] in metres)");
  const json& value = object.at(key);
  if (!value.is_array() || value.size() != 3) {
    fail(where + "." + key, "expected [x, y, z] in metres, got " + value.dump());
  }
  Eigen::Vector3d v;
  for (int axis = 0; axis < 3; ++axis) {
    if (!value[axis].is_number() || !std::isfinite(value[axis].get<double>())) {
      fail(where + "." + key, "expected finite numbers, got " + value.dump());
    }
    v[axis] = value[axis].get<double>();
  }
  return v;
}

void reject_unknown_keys(const json& object, const std::set<std::string>& known,
                         const std::string& where) {
  for (const auto& item : object.items()) {
    if (!known.count(item.key())) fail(where + "." + item.key(), "unknown key");
  }
}

FilterSpec crop_box_from_json(const json& object, const std::string& where) {
  reject_unknown_keys(object, {"type", "min", "max", "remove"}, where);
  CropBoxFilter filter;
  filter.min_m = vector_field(object, "min", where);
  filter.max_m = vector_field(object, "max", where);
  if ((filter.min_m.array() > filter.max_m.array()).any()) fail(where, "min must be <= max");
  const std::string remove = object.value("remove", std::string("outside"));
  if (remove != "inside" && remove != "outside") {
    fail(where + ".remove", "expected \"inside\" or \"outside\", got \"" + remove + "\"");
  }
  filter.remove_inside = remove == "inside";
  return filter;
}

FilterSpec filter_from_json(const json& object, const std::string& where) {
  if (!object.is_object()) fail(where, "expected an object, got " + object.dump());
  if (!object.contains("type") || !object.at("type").is_string()) {
    fail(where + ".type", "missing (expected crop_box, voxel_grid, ror or dror)");
  }
  const std::string type = object.at("type").get<std::string>();
  if (type == "crop_box") return crop_box_from_json(object, where);
  if (type == "voxel_grid") {
    reject_unknown_keys(object, {"type", "leaf"}, where);
    return VoxelGridFilter{number_field(object, "leaf", VoxelGridFilter{}.leaf_m, where, true)};
  }
  if (type == "ror") {
    reject_unknown_keys(object, {"type", "radius", "min_neighbors"}, where);
    const RadiusOutlierFilter defaults;
    return RadiusOutlierFilter{number_field(object, "radius", defaults.radius_m, where, true),
                               count_field(object, "min_neighbors", defaults.min_neighbors, where)};
  }
  if (type == "dror") {
    reject_unknown_keys(object, {"type", "beta", "alpha_deg", "k_min", "sr_min"}, where);
    const DrorFilter defaults;
    return DrorFilter{number_field(object, "beta", defaults.beta, where, true),
                      number_field(object, "alpha_deg", defaults.alpha_deg, where, true),
                      count_field(object, "k_min", defaults.k_min, where),
                      number_field(object, "sr_min", defaults.sr_min_m, where, true)};
  }
  fail(where + ".type",
       "unknown filter \"" + type + "\" (expected crop_box, voxel_grid, ror or dror)");
}

template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;

json vector_json(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

}  // namespace

bool FilterChain::has_dror() const {
  for (const FilterSpec& filter : filters) {
    if (std::holds_alternative<DrorFilter>(filter)) return true;
  }
  return false;
}

std::string filter_type(const FilterSpec& filter) {
  return std::visit(Overloaded{[](const CropBoxFilter&) { return std::string("crop_box"); },
                               [](const VoxelGridFilter&) { return std::string("voxel_grid"); },
                               [](const RadiusOutlierFilter&) { return std::string("ror"); },
                               [](const DrorFilter&) { return std::string("dror"); }},
                    filter);
}

std::vector<FilterStep> apply_filter_chain(const FilterChain& chain, PointCloud& cloud,
                                           int threads) {
  std::vector<FilterStep> steps;
  for (const FilterSpec& filter : chain.filters) {
    FilterStep step{filter_type(filter), cloud.size(), 0};
    std::visit(
        Overloaded{[&](const CropBoxFilter& f) { apply_crop_box(f, cloud); },
                   [&](const VoxelGridFilter& f) { apply_voxel_grid(f, cloud); },
                   [&](const RadiusOutlierFilter& f) { apply_radius_outlier(f, cloud, threads); },
                   [&](const DrorFilter& f) { apply_dror(f, cloud, threads); }},
        filter);
    step.points_out = cloud.size();
    steps.push_back(step);
  }
  return steps;
}

FilterChain filter_chain_from_json(const json& value, const std::string& where) {
  if (!value.is_array()) fail(where, "expected an array of filters, got " + value.dump());
  FilterChain chain;
  for (size_t i = 0; i < value.size(); ++i) {
    chain.filters.push_back(filter_from_json(value[i], where + "[" + std::to_string(i) + "]"));
  }
  return chain;
}

json filter_chain_to_json(const FilterChain& chain) {
  json out = json::array();
  for (const FilterSpec& filter : chain.filters) {
    out.push_back(std::visit(Overloaded{[](const CropBoxFilter& f) {
                                          return json{
                                              {"type", "crop_box"},
                                              {"min", vector_json(f.min_m)},
                                              {"max", vector_json(f.max_m)},
                                              {"remove", f.remove_inside ? "inside" : "outside"}};
                                        },
                                        [](const VoxelGridFilter& f) {
                                          return json{{"type", "voxel_grid"}, {"leaf", f.leaf_m}};
                                        },
                                        [](const RadiusOutlierFilter& f) {
                                          return json{{"type", "ror"},
                                                      {"radius", f.radius_m},
                                                      {"min_neighbors", f.min_neighbors}};
                                        },
                                        [](const DrorFilter& f) {
                                          return json{{"type", "dror"},
                                                      {"beta", f.beta},
                                                      {"alpha_deg", f.alpha_deg},
                                                      {"k_min", f.k_min},
                                                      {"sr_min", f.sr_min_m}};
                                        }},
                             filter));
  }
  return out;
}

namespace {

FilterChain table_iv_scan_filters(double keep_half_extent_m, double alpha_deg) {
  const Eigen::Vector3d keep = Eigen::Vector3d::Constant(keep_half_extent_m);
  const Eigen::Vector3d vessel = Eigen::Vector3d::Constant(2.0);
  FilterChain chain;
  chain.filters.push_back(CropBoxFilter{-keep, keep, false});
  chain.filters.push_back(CropBoxFilter{-vessel, vessel, true});
  chain.filters.push_back(DrorFilter{3.0, alpha_deg, 4, 0.01});
  return chain;
}

}  // namespace

FilterChain table_iv_lidar_scan_filters() { return table_iv_scan_filters(60.0, 0.2); }
FilterChain table_iv_sonar_scan_filters() { return table_iv_scan_filters(30.0, 0.5); }

}  // namespace keel::mapping
