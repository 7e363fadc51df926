#include "core/geodesy.h"

#include <proj.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace keel {

namespace {

std::string number(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%.12g", value);
  return text;
}

}  // namespace

struct LocalEnuFrame::Impl {
  PJ_CONTEXT* context = nullptr;
  PJ* pipeline = nullptr;

  ~Impl() {
    if (pipeline) proj_destroy(pipeline);
    if (context) proj_context_destroy(context);
  }

  PJ_COORD run(PJ_DIRECTION direction, PJ_COORD in) const {
    const PJ_COORD out = proj_trans(pipeline, direction, in);
    if (!std::isfinite(out.xyz.x) || !std::isfinite(out.xyz.y) || !std::isfinite(out.xyz.z))
      throw std::invalid_argument(std::string("geodesy: PROJ could not transform the point: ") +
                                  proj_context_errno_string(context, proj_errno(pipeline)));
    return out;
  }
};

LocalEnuFrame::LocalEnuFrame(const GeodeticPoint& origin) : origin_(origin) {
  if (!std::isfinite(origin.latitude_deg) || !std::isfinite(origin.longitude_deg) ||
      !std::isfinite(origin.height_m) || std::abs(origin.latitude_deg) > 90.0 ||
      origin.longitude_deg < -180.0 || origin.longitude_deg > 360.0)
    throw std::invalid_argument("geodesy: origin latitude_deg " + number(origin.latitude_deg) +
                                ", longitude_deg " + number(origin.longitude_deg) + ", height_m " +
                                number(origin.height_m) +
                                " is not a WGS 84 point (latitude in [-90, 90], longitude in "
                                "[-180, 360], finite)");
  impl_ = std::make_unique<Impl>();
  impl_->context = proj_context_create();
  // Input: longitude, latitude (degrees), ellipsoidal height; the pipeline needs no grid or
  // database file: both steps are closed forms on the WGS 84 ellipsoid.
  const std::string definition =
      "+proj=pipeline +step +proj=unitconvert +xy_in=deg +xy_out=rad"
      " +step +proj=cart +ellps=WGS84"
      " +step +proj=topocentric +ellps=WGS84 +lat_0=" +
      number(origin.latitude_deg) + " +lon_0=" + number(origin.longitude_deg) +
      " +h_0=" + number(origin.height_m);
  impl_->pipeline = proj_create(impl_->context, definition.c_str());
  if (!impl_->pipeline)
    throw std::invalid_argument(
        "geodesy: PROJ refused the topocentric pipeline (" + definition +
        "): " + proj_context_errno_string(impl_->context, proj_context_errno(impl_->context)));
}

LocalEnuFrame::~LocalEnuFrame() = default;
LocalEnuFrame::LocalEnuFrame(LocalEnuFrame&&) noexcept = default;
LocalEnuFrame& LocalEnuFrame::operator=(LocalEnuFrame&&) noexcept = default;

Eigen::Vector3d LocalEnuFrame::to_enu(const GeodeticPoint& point) const {
  const PJ_COORD out =
      impl_->run(PJ_FWD, proj_coord(point.longitude_deg, point.latitude_deg, point.height_m, 0.0));
  return {out.xyz.x, out.xyz.y, out.xyz.z};
}

GeodeticPoint LocalEnuFrame::to_geodetic(const Eigen::Vector3d& enu_m) const {
  const PJ_COORD out = impl_->run(PJ_INV, proj_coord(enu_m.x(), enu_m.y(), enu_m.z(), 0.0));
  return {out.lpz.phi, out.lpz.lam, out.lpz.z};
}

}  // namespace keel
