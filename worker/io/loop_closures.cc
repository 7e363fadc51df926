#include "worker/io/loop_closures.h"

#include <cmath>

#include "worker/io/csv_reader.h"
#include "worker/io/text_writer.h"

namespace keel::io {

std::vector<LoopClosure> read_loop_closures(const std::filesystem::path& path) {
  CsvReader csv(path, {"t_i", "t_j", "x", "y", "z", "qx", "qy", "qz", "qw", "sigma_t", "sigma_r"});
  std::vector<LoopClosure> loops;
  while (csv.next()) {
    LoopClosure loop;
    loop.t_i_ns = csv.time(0);
    loop.t_j_ns = csv.time(1);
    if (loop.t_i_ns == loop.t_j_ns) csv.fail("t_i equals t_j: a loop closure joins two keyframes");
    const Eigen::Vector3d t(csv.number(2), csv.number(3), csv.number(4));
    const Eigen::Quaterniond q(csv.number(8), csv.number(5), csv.number(6), csv.number(7));
    if (std::abs(q.norm() - 1.0) > 1e-3)
      csv.fail("quaternion: expected unit norm, |q| = " + std::to_string(q.norm()));
    loop.T_body_i_body_j = make_pose(q, t);
    loop.sigma_t_m = csv.number(9);
    loop.sigma_r_rad = csv.number(10);
    if (!(loop.sigma_t_m > 0.0) || !(loop.sigma_r_rad > 0.0))
      csv.fail("sigma_t and sigma_r: expected positive numbers");
    loops.push_back(loop);
  }
  return loops;
}

void write_loop_closures(const std::filesystem::path& path, const std::vector<LoopClosure>& loops) {
  TextWriter w(path);
  w.text("t_i,t_j,x,y,z,qx,qy,qz,qw,sigma_t,sigma_r\n");
  for (const auto& loop : loops) {
    const Eigen::Vector3d t = loop.T_body_i_body_j.translation();
    const Eigen::Quaterniond q(loop.T_body_i_body_j.rotation());
    w.seconds(loop.t_i_ns).text(",").seconds(loop.t_j_ns);
    for (double x :
         {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w(), loop.sigma_t_m, loop.sigma_r_rad})
      w.text(",").number(x);
    w.text("\n");
  }
  w.close();
}

}  // namespace keel::io
