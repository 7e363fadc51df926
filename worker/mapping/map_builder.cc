#include "worker/mapping/map_builder.h"

#include <algorithm>
#include <condition_variable>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "worker/mapping/cloud_ops.h"
#include "worker/mapping/voxel_accumulator.h"

namespace keel::mapping {

struct MapBuilder::SensorState {
  std::string name;
  SensorMapOptions options;
  SensorMapStats stats;
  PointCloud batch;  // the current intermediary map, in W (Eq. (22))
  int batch_scans = 0;
  PointCloud map;  // the sensor's map in W (the final map after finish())
  // Set when the final chain starts with a voxel grid: the map is kept as voxel sums.
  std::optional<VoxelAccumulator> voxel_map;
};

namespace {

void add_steps(StageStats& stage, const std::vector<FilterStep>& steps) {
  ++stage.applications;
  if (stage.steps.empty()) {
    stage.steps = steps;
    return;
  }
  for (size_t i = 0; i < steps.size(); ++i) {
    stage.steps[i].points_in += steps[i].points_in;
    stage.steps[i].points_out += steps[i].points_out;
  }
}

void check_stage_filters(const SensorMapOptions& options, const std::string& sensor) {
  if (options.intermediary_filters.has_dror() || options.final_filters.has_dror()) {
    throw std::invalid_argument("map filters of sensor '" + sensor +
                                "': DROR needs the scan origin and may only be a scan filter");
  }
}

bool starts_with_voxel_grid(const FilterChain& chain) {
  return !chain.empty() && std::holds_alternative<VoxelGridFilter>(chain.filters.front());
}

}  // namespace

SensorMapOptions sensor_map_options_from_json(const nlohmann::json& json, const std::string& where,
                                              SensorMapOptions defaults) {
  if (!json.is_object()) {
    throw std::invalid_argument(where + ": expected an object, got " + json.dump());
  }
  for (const auto& item : json.items()) {
    const std::string key = item.key();
    const std::string path = where + "." + key;
    if (key == "scan_filters") {
      defaults.scan_filters = filter_chain_from_json(item.value(), path);
    } else if (key == "intermediary_filters") {
      defaults.intermediary_filters = filter_chain_from_json(item.value(), path);
    } else if (key == "final_filters") {
      defaults.final_filters = filter_chain_from_json(item.value(), path);
    } else if (key == "deskew") {
      if (!item.value().is_boolean()) {
        throw std::invalid_argument(path + ": expected true or false, got " + item.value().dump());
      }
      defaults.deskew = item.value().get<bool>();
    } else {
      throw std::invalid_argument(path +
                                  ": unknown key (expected scan_filters, "
                                  "intermediary_filters, final_filters or deskew)");
    }
  }
  return defaults;
}

nlohmann::json to_json(const SensorMapOptions& options) {
  return {{"scan_filters", filter_chain_to_json(options.scan_filters)},
          {"intermediary_filters", filter_chain_to_json(options.intermediary_filters)},
          {"final_filters", filter_chain_to_json(options.final_filters)},
          {"deskew", options.deskew}};
}

MapBuilder::MapBuilder(const TransformTree& tree, MapBuilderOptions options)
    : tree_(tree), options_(std::move(options)) {
  if (options_.scans_per_intermediary < 1) {
    throw std::invalid_argument("map.scans_per_intermediary (N_I): expected >= 1, got " +
                                std::to_string(options_.scans_per_intermediary));
  }
  const double merge = options_.final_voxel_merge_radius_leaves;
  if (!(merge >= 0.0 && merge <= VoxelAccumulator::kMaxMergeLeaves)) {
    throw std::invalid_argument("map.final_voxel_merge_radius_leaves: expected a number in [0, " +
                                std::to_string(VoxelAccumulator::kMaxMergeLeaves) + "], got " +
                                std::to_string(merge));
  }
  check_stage_filters(options_.default_sensor, "(default)");
  for (const auto& [sensor, sensor_options] : options_.sensors) {
    check_stage_filters(sensor_options, sensor);
  }
}

MapBuilder::~MapBuilder() = default;

MapBuilder::SensorState& MapBuilder::state_for(const std::string& sensor) {
  auto found = states_.find(sensor);
  if (found != states_.end()) return *found->second;
  auto state = std::make_unique<SensorState>();
  state->name = sensor;
  const auto listed = options_.sensors.find(sensor);
  state->options = listed != options_.sensors.end() ? listed->second : options_.default_sensor;
  if (starts_with_voxel_grid(state->options.final_filters) && !options_.final_sink) {
    const double leaf_m =
        std::get<VoxelGridFilter>(state->options.final_filters.filters.front()).leaf_m;
    state->voxel_map.emplace(leaf_m, leaf_m * options_.final_voxel_merge_radius_leaves);
  }
  return *states_.emplace(sensor, std::move(state)).first->second;
}

const MapBuilder::SensorState& MapBuilder::existing_state(const std::string& sensor) const {
  const auto found = states_.find(sensor);
  if (found == states_.end()) {
    throw std::invalid_argument("map builder: no scans of sensor '" + sensor + "'");
  }
  return *found->second;
}

struct MapBuilder::PreparedScan {
  SensorState* state = nullptr;
  PointCloud points;  // in W, after the scan filters
  size_t points_in = 0;
  size_t non_finite_points = 0;
  bool outside_trajectory = false;
  std::vector<FilterStep> scan_steps;
};

MapBuilder::PreparedScan MapBuilder::prepare(const std::string& sensor, SensorState& state,
                                             PointCloud scan, int filter_threads) const {
  check_field_sizes(scan, ("scan of sensor '" + sensor + "'").c_str());
  PreparedScan out;
  out.state = &state;
  out.points_in = scan.size();
  out.non_finite_points = remove_non_finite(scan);

  // Motion compensation into the sensor frame at the scan stamp (Sec. VI-A2).
  Pose3 T_world_sensor;
  try {
    if (state.options.deskew) {
      T_world_sensor = deskew_scan(tree_, sensor, scan, options_.deskew);
    } else {
      T_world_sensor = tree_.T_world_sensor(sensor, scan.t_ns);
    }
  } catch (const std::out_of_range&) {
    if (!options_.skip_scans_outside_trajectory) throw;
    out.outside_trajectory = true;
    return out;
  }
  // Per-point offsets refer to this scan's stamp; a world map mixes stamps, so they go.
  scan.time_s.clear();

  // Stage 1: filters on the scan in its sensor frame (crop box about the sensor, DROR).
  out.scan_steps = apply_filter_chain(state.options.scan_filters, scan, filter_threads);
  // Eq. (20) -> W V_{WS_i,K_j}.
  transform_points(scan, T_world_sensor);
  scan.frame = "world";
  out.points = std::move(scan);
  return out;
}

void MapBuilder::commit(PreparedScan prepared) {
  SensorState& state = *prepared.state;
  ++state.stats.scans;
  state.stats.points_in += prepared.points_in;
  state.stats.non_finite_points += prepared.non_finite_points;
  if (prepared.outside_trajectory) {
    ++state.stats.scans_outside_trajectory;
    return;
  }
  add_steps(state.stats.scan_stage, prepared.scan_steps);
  append_points(state.batch, prepared.points);
  if (++state.batch_scans >= options_.scans_per_intermediary) flush_intermediary(state);
}

void MapBuilder::add_scan(const std::string& sensor, PointCloud scan) {
  if (finished_) throw std::logic_error("map builder: add_scan after finish()");
  tree_.T_body_sensor(sensor);  // an unknown sensor is an error, not a skipped scan
  SensorState& state = state_for(sensor);
  commit(prepare(sensor, state, std::move(scan), options_.threads));
}

void MapBuilder::add_scans(const ScanFeed& next) {
  if (finished_) throw std::logic_error("map builder: add_scans after finish()");
  const int workers = std::max(1, options_.threads);
  // Prepared scans wait in `ready` for their turn; whichever thread hands in the scan that is
  // next in feed order commits it and every consecutive one already waiting, while the other
  // threads go on preparing. No thread sleeps until its own turn comes (it did before: on
  // 2 cores the scan phase kept ~1.45 of them busy). A thread takes a new scan only while
  // fewer than kMaxReadyPerWorker scans per thread wait, so at most that many plus one per
  // thread are held, however uneven the scans are.
  constexpr size_t kMaxReadyPerWorker = 2;
  const size_t max_ready = kMaxReadyPerWorker * static_cast<size_t>(workers);
  std::mutex feed_mutex;  // serializes `next` (and state_for)
  std::mutex mutex;       // guards everything below
  std::condition_variable changed;
  std::map<uint64_t, PreparedScan> ready;
  uint64_t fed = 0, next_commit = 0;
  bool feed_done = false, committing = false;
  std::exception_ptr error;

  auto fail = [&](std::exception_ptr e) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!error) error = e;
    changed.notify_all();
  };
  // Commits ready scans in feed order until the next one is not ready; called with `lock` held
  // and committing == false.
  auto commit_in_order = [&](std::unique_lock<std::mutex>& lock) {
    committing = true;
    while (!error) {
      const auto it = ready.find(next_commit);
      if (it == ready.end()) break;
      PreparedScan scan = std::move(it->second);
      ready.erase(it);
      changed.notify_all();  // room in `ready`
      lock.unlock();
      try {
        commit(std::move(scan));
      } catch (...) {
        lock.lock();
        if (!error) error = std::current_exception();
        break;
      }
      lock.lock();
      ++next_commit;
    }
    committing = false;
    changed.notify_all();
  };
  auto worker = [&] {
    std::string sensor;
    PointCloud scan;
    while (true) {
      {
        std::unique_lock<std::mutex> lock(mutex);
        changed.wait(lock, [&] { return ready.size() < max_ready || error != nullptr; });
        if (error) return;
      }
      uint64_t sequence = 0;
      SensorState* state = nullptr;
      try {
        std::lock_guard<std::mutex> lock(feed_mutex);
        if (feed_done) return;
        {
          std::lock_guard<std::mutex> check(mutex);
          if (error) return;
        }
        scan = PointCloud{};
        if (!next(sensor, scan)) {
          feed_done = true;
          return;
        }
        tree_.T_body_sensor(sensor);  // an unknown sensor is an error
        state = &state_for(sensor);
        sequence = fed++;
      } catch (...) {
        fail(std::current_exception());
        return;
      }
      // Scan-level parallelism: each scan's filters run on one thread.
      std::optional<PreparedScan> prepared;
      try {
        prepared.emplace(
            prepare(sensor, *state, std::move(scan), workers > 1 ? 1 : options_.threads));
      } catch (...) {
        fail(std::current_exception());
        return;
      }
      std::unique_lock<std::mutex> lock(mutex);
      if (error) return;
      try {
        ready.emplace(sequence, std::move(*prepared));
      } catch (...) {  // bad_alloc: the scan is lost, so nothing after it may commit
        error = std::current_exception();
        changed.notify_all();
        return;
      }
      if (!committing) commit_in_order(lock);
    }
  };
  std::vector<std::thread> threads;
  try {
    for (int w = 1; w < workers; ++w) threads.emplace_back(worker);
  } catch (...) {  // no thread: stop the ones started before they outlive this frame
    fail(std::current_exception());
  }
  worker();
  for (std::thread& thread : threads) thread.join();
  if (error) std::rethrow_exception(error);
  // Every thread has returned without an error: the feed ended and each prepared scan was
  // handed in, and the last hand-in found no committer running, so all were committed.
}

void MapBuilder::flush_intermediary(SensorState& state) {
  if (state.batch_scans == 0) return;
  // Stage 2 on the intermediary map of Eq. (22).
  add_steps(state.stats.intermediary_stage,
            apply_filter_chain(state.options.intermediary_filters, state.batch, options_.threads));
  ++state.stats.intermediary_maps;
  if (options_.final_sink) {
    options_.final_sink(state.name, state.batch);
  } else if (state.voxel_map) {
    state.voxel_map->add(state.batch);
  } else {
    append_points(state.map, state.batch);
  }
  state.batch = PointCloud{};  // release the batch's memory
  state.batch_scans = 0;
}

void MapBuilder::finish() {
  if (finished_) return;
  finished_ = true;
  for (auto& [sensor, state_ptr] : states_) {
    SensorState& state = *state_ptr;
    flush_intermediary(state);  // the last, partial intermediary map
    if (options_.final_sink) continue;  // stage 3 runs on the sink's side
    // Stage 3 on the sensor's map.
    FilterChain rest = state.options.final_filters;
    std::vector<FilterStep> steps;
    if (state.voxel_map) {
      // The first filter (the voxel grid) already ran as the map streamed in.
      state.map = state.voxel_map->centroids();
      steps.push_back(FilterStep{"voxel_grid", state.voxel_map->points_added(), state.map.size()});
      state.voxel_map.reset();
      rest.filters.erase(rest.filters.begin());
    }
    state.map.frame = "world";
    const std::vector<FilterStep> rest_steps =
        apply_filter_chain(rest, state.map, options_.threads);
    steps.insert(steps.end(), rest_steps.begin(), rest_steps.end());
    add_steps(state.stats.final_stage, steps);
    state.stats.points_out = state.map.size();
  }
}

std::vector<std::string> MapBuilder::sensors() const {
  std::vector<std::string> names;
  for (const auto& [sensor, state] : states_) names.push_back(sensor);
  return names;
}

const PointCloud& MapBuilder::sensor_map(const std::string& sensor) const {
  if (!finished_) throw std::logic_error("map builder: sensor_map before finish()");
  return existing_state(sensor).map;
}

const SensorMapStats& MapBuilder::stats(const std::string& sensor) const {
  return existing_state(sensor).stats;
}

PointCloud MapBuilder::combined_map() const {
  if (!finished_) throw std::logic_error("map builder: combined_map before finish()");
  PointCloud combined;
  combined.frame = "world";
  size_t total = 0;
  for (const auto& [sensor, state] : states_) total += state->map.size();
  combined.xyz.reserve(total);
  for (const auto& [sensor, state] : states_) append_points(combined, state->map);
  return combined;
}

}  // namespace keel::mapping
