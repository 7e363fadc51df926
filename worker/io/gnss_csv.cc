#include "worker/io/gnss_csv.h"

#include <cmath>
#include <limits>

#include "worker/io/csv_reader.h"
#include "worker/io/text_writer.h"

namespace keel::io {

GnssSeries read_gnss_csv(const std::filesystem::path& path) {
  CsvReader csv(path, {"t", "latitude", "longitude", "height", "status"},
                {"sigma_e", "sigma_n", "sigma_u"});
  if (csv.num_columns() != 5 && csv.num_columns() != 8)
    csv.fail("give all three of sigma_e, sigma_n, sigma_u or none");
  GnssSeries out;
  while (csv.next()) {
    GnssSample s;
    s.t_ns = csv.time(0);
    csv.check_increasing(s.t_ns);
    const double status = csv.number(4);
    if (status != -1.0 && status != 0.0 && status != 1.0 && status != 2.0)
      csv.fail("column 'status': expected -1 (no fix), 0 (fix), 1 (SBAS) or 2 (GBAS)");
    s.status = static_cast<int>(status);
    const bool fix = s.status >= 0;
    s.latitude_deg = csv.number(1, !fix);
    s.longitude_deg = csv.number(2, !fix);
    s.height_m = csv.number(3, !fix);
    if (fix && std::abs(s.latitude_deg) > 90.0)
      csv.fail("column 'latitude': not in [-90, 90] degrees");
    if (fix && std::abs(s.longitude_deg) > 180.0)
      csv.fail("column 'longitude': not in [-180, 180] degrees");
    if (csv.has_column(7)) {
      const double sigma[3] = {csv.number(5, true), csv.number(6, true), csv.number(7, true)};
      const int known = std::isfinite(sigma[0]) + std::isfinite(sigma[1]) + std::isfinite(sigma[2]);
      if (known != 0 && known != 3) csv.fail("sigma_e, sigma_n, sigma_u: all finite or all nan");
      for (int i = 0; i < 3; ++i)
        if (known == 3 && sigma[i] < 0.0) csv.fail("a sigma column is negative");
      s.covariance_known = known == 3 && fix;
      if (s.covariance_known)
        for (int i = 0; i < 3; ++i) s.covariance_enu_m2[4 * i] = sigma[i] * sigma[i];
    }
    out.push_back(s);
  }
  return out;
}

void write_gnss_csv(const std::filesystem::path& path, const GnssSeries& samples,
                    bool with_sigmas) {
  TextWriter w(path);
  w.text(with_sigmas ? "t,latitude,longitude,height,status,sigma_e,sigma_n,sigma_u\n"
                     : "t,latitude,longitude,height,status\n");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& s : samples) {
    w.seconds(s.t_ns);
    w.text(",").number(s.latitude_deg).text(",").number(s.longitude_deg);
    w.text(",").number(s.height_m).text(",").text(std::to_string(s.status));
    if (with_sigmas)
      for (int i = 0; i < 3; ++i)
        w.text(",").number(s.covariance_known ? std::sqrt(s.covariance_enu_m2[4 * i]) : nan);
    w.text("\n");
  }
  w.close();
}

}  // namespace keel::io
