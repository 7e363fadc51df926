// Seeds for the file-format fuzzers (fuzz_scan_file, fuzz_mesh, fuzz_trajectory): one small
// valid file of every encoding each reader accepts, prefixed by the harness's selector byte.
// libFuzzer rarely turns "binary" into "ascii" by mutation, so a corpus that starts from one
// encoding leaves the others' parsers unfuzzed. Each seed is read back by Keel's reader before
// it is written: a seed the reader refuses is an error (fuzz_seeds fails).
#pragma once

#include <filesystem>

namespace keel::fuzz {

// PCD ascii, binary and binary_compressed; PLY ascii and binary; with intensity, ring and
// per-point time in several units; each also with a non-finite point. Returns the count.
int write_scan_seeds(const std::filesystem::path& dir);

// PLY ascii, binary little and big endian (normals, colours, extra elements, polygons), OBJ
// (every corner form, relative indices, groups), STL ascii and binary (one whose header
// starts with "solid"), OFF and COFF; and PLY headers for the header parser.
int write_mesh_seeds(const std::filesystem::path& dir);

// Each sensor CSV stream (DVL with and without its `valid` column, ranges with `nan`) and
// loop closures, with the selector fuzz_csv_streams reads them with.
int write_csv_seeds(const std::filesystem::path& dir);

// Mission bundles: ustar, GNU and pax tars (long and non-ASCII names, folders, links, a
// device), gzip-compressed, and hostile ones (absolute and `..` names, links leaving the
// bundle). libarchive is not instrumented: libFuzzer steers only through Keel's check of what
// it returns, so each kind of member must be in the seeds.
int write_bundle_seeds(const std::filesystem::path& dir);

// TUM (with comments) and KITTI pose files.
int write_trajectory_seeds(const std::filesystem::path& dir);

}  // namespace keel::fuzz
