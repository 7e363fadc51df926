#include "worker/stages/map/tiled_outputs.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "core/ordered_parallel.h"
#include "core/replaced_file.h"
#include "worker/io/cloud/ply_cloud_writer.h"

namespace keel::pipeline {
namespace {

using mapping::TileKey;

bool every_part_has_intensity(const TiledMaps& maps, const std::vector<std::string>& parts) {
  bool any = false;
  for (const auto& part : parts) {
    if (maps.points(part) == 0) continue;
    any = true;
    if (!maps.has_intensity(part)) return false;
  }
  return any;
}

// A tile's points of every part: the cores in part order, then (with_halo) the halos.
PointCloud load_parts(const TiledMaps& maps, const std::vector<std::string>& parts,
                      const TileKey& tile, bool with_halo, size_t* owned) {
  PointCloud out;
  out.frame = "world";
  std::vector<PointCloud> halos;
  *owned = 0;
  for (const auto& part : parts) {
    size_t core = 0;
    PointCloud points = maps.load(part, tile, with_halo, &core);
    out.xyz.insert(out.xyz.end(), points.xyz.begin(), points.xyz.begin() + core);
    *owned += core;
    if (with_halo) {
      points.xyz.erase(points.xyz.begin(), points.xyz.begin() + core);
      halos.push_back(std::move(points));
    }
  }
  for (const auto& halo : halos) out.xyz.insert(out.xyz.end(), halo.xyz.begin(), halo.xyz.end());
  return out;
}

}  // namespace

mapping::MapMetrics tiled_map_metrics(const TiledMaps& maps, const std::vector<std::string>& parts,
                                      const std::vector<TileKey>& tiles,
                                      const mapping::MapMetricsOptions& options) {
  uint64_t total = 0;
  for (const auto& part : parts) total += maps.points(part);
  const uint64_t queries =
      options.max_query_points > 0 ? std::min<uint64_t>(options.max_query_points, total) : total;
  // Query q reads map point floor(q total / queries) (compute_point_metrics' stride). Each tile's
  // first map index, for the queries that fall in it.
  std::vector<uint64_t> first(tiles.size() + 1, 0);
  for (size_t t = 0; t < tiles.size(); ++t)
    first[t + 1] = first[t] + maps.tile_points(parts, tiles[t], false);
  // (The products stay below 2^64 for maps below ~4e9 points with every point a query, as in
  // compute_point_metrics.)
  const auto query_point = [&](uint64_t q) { return q * total / queries; };
  const auto first_query_at = [&](uint64_t index) {  // the first q with query_point(q) >= index
    return (index * queries + total - 1) / total;
  };
  mapping::PointMetrics all;
  all.query_index.resize(queries);
  all.surface_density.resize(queries);
  all.roughness.resize(queries);
  all.planarity.resize(queries);
  mapping::MapMetricsOptions tile_options = options;
  tile_options.threads = 1;  // tiles side by side instead
  struct TileQueries {
    uint64_t first_query = 0;
    mapping::PointMetrics metrics;
  };
  ordered_parallel<TileQueries>(
      tiles.size(), options.threads, 2 * static_cast<size_t>(std::max(1, options.threads)),
      [&](size_t t) {
        TileQueries out;
        if (queries == 0) return out;
        out.first_query = first_query_at(first[t]);
        std::vector<size_t> local;
        for (uint64_t q = out.first_query; q < queries && query_point(q) < first[t + 1]; ++q)
          local.push_back(static_cast<size_t>(query_point(q) - first[t]));
        if (local.empty()) return out;
        size_t owned = 0;
        const PointCloud points = load_parts(maps, parts, tiles[t], true, &owned);
        if (owned != first[t + 1] - first[t])
          throw std::logic_error("tiled metrics: tile " + tiles[t].to_string() + " holds " +
                                 std::to_string(owned) + " points, counted " +
                                 std::to_string(first[t + 1] - first[t]));
        out.metrics = mapping::compute_point_metrics_at(points.xyz, local, tile_options);
        return out;
      },
      [&](size_t t, TileQueries result) {
        for (size_t k = 0; k < result.metrics.query_index.size(); ++k) {
          const uint64_t q = result.first_query + k;
          all.query_index[q] = first[t] + result.metrics.query_index[k];
          all.surface_density[q] = result.metrics.surface_density[k];
          all.roughness[q] = result.metrics.roughness[k];
          all.planarity[q] = result.metrics.planarity[k];
        }
      });
  mapping::MapMetrics metrics;
  metrics.points = total;
  metrics.query_points = queries;
  metrics.radius_m = options.radius_m;
  metrics.surface_density = mapping::summarize(all.surface_density, options.histogram_bins);
  metrics.roughness = mapping::summarize(all.roughness, options.histogram_bins);
  metrics.planarity = mapping::summarize(all.planarity, options.histogram_bins);
  return metrics;
}

void write_tiled_ply(const TiledMaps& maps, const std::vector<std::string>& parts,
                     const std::vector<TileKey>& tiles, const std::filesystem::path& path,
                     const std::function<void()>& check_canceled) {
  uint64_t total = 0;
  for (const auto& part : parts) total += maps.points(part);
  const bool intensity = every_part_has_intensity(maps, parts);
  keel::ReplacedFile file(path);
  const std::string header = io::ply_cloud_header(total, intensity, false, false);
  file.append(header.data(), header.size());
  const size_t point_bytes = intensity ? 16 : 12;
  std::vector<char> chunk;
  uint64_t written = 0;
  for (const TileKey& tile : tiles) {
    if (check_canceled) check_canceled();
    for (const auto& part : parts) {
      const PointCloud points = maps.load(part, tile);
      chunk.resize(points.size() * point_bytes);
      char* at = chunk.data();
      for (size_t k = 0; k < points.size(); ++k) {
        std::memcpy(at, points.xyz[k].data(), 12);
        if (intensity) std::memcpy(at + 12, &points.intensity[k], 4);
        at += point_bytes;
      }
      file.append(chunk.data(), chunk.size());
      written += points.size();
    }
  }
  if (written != total)
    throw std::logic_error("tiled PLY " + path.filename().string() + ": wrote " +
                           std::to_string(written) + " of " + std::to_string(total) + " points");
  file.commit();
}

PointCloud gather_tiled_map(const TiledMaps& maps, const std::vector<std::string>& parts,
                            const std::vector<TileKey>& tiles) {
  const bool intensity = every_part_has_intensity(maps, parts);
  uint64_t total = 0;
  for (const auto& part : parts) total += maps.points(part);
  PointCloud out;
  out.frame = "world";
  out.xyz.reserve(total);
  if (intensity) out.intensity.reserve(total);
  for (const TileKey& tile : tiles)
    for (const auto& part : parts) {
      PointCloud points = maps.load(part, tile);
      out.xyz.insert(out.xyz.end(), points.xyz.begin(), points.xyz.end());
      if (intensity)
        out.intensity.insert(out.intensity.end(), points.intensity.begin(), points.intensity.end());
    }
  return out;
}

MapTilesetResult write_tiled_tileset(const TiledMaps& maps, const std::vector<std::string>& parts,
                                     const std::vector<TileKey>& tiles, const std::string& map,
                                     const std::filesystem::path& tar,
                                     const mapping::LodOptions& options,
                                     const std::function<void()>& check_canceled) {
  const bool intensity = every_part_has_intensity(maps, parts);
  const bool sensor = parts.size() > 1;
  std::vector<io::PntsAttribute> attributes;
  if (intensity) attributes.push_back({"intensity", io::PntsAttribute::Type::kFloat});
  if (sensor) attributes.push_back({"sensor", io::PntsAttribute::Type::kUnsignedByte});
  LodTileSource source{tiles, [&](const TileKey& tile) {
                         auto points = mapping::LodPoints::with_attributes(attributes.size());
                         for (size_t p = 0; p < parts.size(); ++p) {
                           const PointCloud part = maps.load(parts[p], tile);
                           points.xyz.insert(points.xyz.end(), part.xyz.begin(), part.xyz.end());
                           size_t a = 0;
                           if (intensity) {
                             points.attributes[a].insert(points.attributes[a].end(),
                                                         part.intensity.begin(),
                                                         part.intensity.end());
                             ++a;
                           }
                           if (sensor)
                             points.attributes[a].resize(points.xyz.size(), static_cast<float>(p));
                         }
                         return points;
                       }};
  nlohmann::json extras = {{"map", map}, {"frame", "world"}};
  if (sensor) extras["sensors"] = parts;
  return write_map_tileset(tar, maps.output_grid(), source, attributes, std::move(extras), options,
                           check_canceled);
}

}  // namespace keel::pipeline
