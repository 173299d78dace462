#include "raycaster.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace handtrack::synth {
namespace {

using Eigen::Vector3d;

constexpr double kNearPlaneMm = 1.0;  // rays start at the pinhole; anything closer is ignored

// Smallest t > near with |t d - c|^2 = r^2, or +inf. The ray is t d (d.z = 1, so t is the depth z).
double ray_sphere(const Vector3d& d, double dd, const Vector3d& c, double r) {
  const double dc = d.dot(c);
  const double disc = dc * dc - dd * (c.squaredNorm() - r * r);
  if (disc < 0.0) return std::numeric_limits<double>::infinity();
  const double s = std::sqrt(disc);
  double t = (dc - s) / dd;
  if (t <= kNearPlaneMm) t = (dc + s) / dd;
  return t > kNearPlaneMm ? t : std::numeric_limits<double>::infinity();
}

// Cone-sphere geometry precomputed once per primitive. With L = |b - a|, u = (b - a) / L and
// sin(alpha) = (r_a - r_b) / L, the hull's lateral surface is the cone rho(h) = r_a / cos(alpha) -
// h tan(alpha) (h = axial coordinate from a, rho = distance from the axis), valid for
// h in [r_a sin(alpha), L + r_b sin(alpha)]; the rest of the hull surface lies on the two spheres.
// Its outward normal is cos(alpha) e_rho + sin(alpha) u.
struct ConeSphereGeometry {
  Vector3d a, b, u;
  double ra, rb, length;
  double sin_a, cos_a, k0, k1;  // k0 = r_a / cos(alpha), k1 = tan(alpha)
  double h_min, h_max;
  bool sphere_only;  // one sphere contains the other (or a == b)
  double au, aa, k_m;  // a.u, |a|^2, m = k0 + k1 (a.u)

  explicit ConeSphereGeometry(const ConeSphere& c)
      : a(c.a), b(c.b), u(Vector3d::UnitZ()), ra(c.radius_a), rb(c.radius_b), length((c.b - c.a).norm()),
        sin_a(0), cos_a(1), k0(0), k1(0), h_min(0), h_max(0), sphere_only(false), au(0), aa(0), k_m(0) {
    if (length <= std::abs(ra - rb) + 1e-9) {
      sphere_only = true;
      if (rb > ra) {
        a = b;
        ra = rb;
      }
      return;
    }
    u = (b - a) / length;
    sin_a = (ra - rb) / length;
    cos_a = std::sqrt(1.0 - sin_a * sin_a);
    k0 = ra / cos_a;
    k1 = sin_a / cos_a;
    h_min = ra * sin_a;
    h_max = length + rb * sin_a;
    au = a.dot(u);
    aa = a.squaredNorm();
    k_m = k0 + k1 * au;
  }

  // First hit along t d: depth t and outward normal. Returns +inf when missed.
  double intersect(const Vector3d& d, Vector3d& normal) const {
    const double dd = d.squaredNorm();
    double best = ray_sphere(d, dd, a, ra);
    int which = 0;
    if (sphere_only) {
      if (std::isfinite(best)) normal = (best * d - a) / ra;
      return best;
    }
    const double tb = ray_sphere(d, dd, b, rb);
    if (tb < best) {
      best = tb;
      which = 1;
    }
    // Lateral cone: |w|^2 - h^2 = (k0 - k1 h)^2 with w = t d - a, h = w.u, written as
    // A t^2 + B t + C = 0 (see the derivation in the class comment).
    const double du = d.dot(u);
    const double da = d.dot(a);
    const double A = dd - du * du * (1.0 + k1 * k1);
    const double B = 2.0 * (-da + du * au + k_m * k1 * du);
    const double C = aa - au * au - k_m * k_m;
    if (std::abs(A) > 1e-12) {
      const double disc = B * B - 4.0 * A * C;
      if (disc >= 0.0) {
        const double s = std::sqrt(disc);
        for (const double t : {(-B - s) / (2.0 * A), (-B + s) / (2.0 * A)}) {
          if (t <= kNearPlaneMm || t >= best) continue;
          const double h = t * du - au;
          if (h < h_min || h > h_max) continue;
          best = t;
          which = 2;
        }
      }
    }
    if (!std::isfinite(best)) return best;
    const Vector3d p = best * d;
    if (which == 0) {
      normal = (p - a) / ra;
    } else if (which == 1) {
      normal = (p - b) / rb;
    } else {
      const Vector3d w = p - a;
      const Vector3d radial = w - w.dot(u) * u;
      const double rho = radial.norm();
      normal = rho > 1e-12 ? Vector3d(cos_a * radial / rho + sin_a * u) : u;
    }
    return best;
  }
};

}  // namespace

Raycaster::Raycaster(const CameraIntrinsics& camera)
    : camera_(camera),
      ray_x_(static_cast<size_t>(camera.width)),
      ray_y_(static_cast<size_t>(camera.height)),
      depth_(static_cast<size_t>(camera.width) * static_cast<size_t>(camera.height)),
      labels_(depth_.size()),
      incidence_(depth_.size()) {
  // Pixel (u, v) looks along the ray through the image point (u, v) itself, matching
  // CameraIntrinsics::project/unproject (no half-pixel offset).
  for (int u = 0; u < camera.width; ++u) ray_x_[static_cast<size_t>(u)] = (u - camera.cx) / camera.fx;
  for (int v = 0; v < camera.height; ++v) ray_y_[static_cast<size_t>(v)] = (v - camera.cy) / camera.fy;
  clear();
}

void Raycaster::clear() {
  std::fill(depth_.begin(), depth_.end(), std::numeric_limits<float>::infinity());
  std::fill(labels_.begin(), labels_.end(), uint8_t{0});
  std::fill(incidence_.begin(), incidence_.end(), 1.0f);
}

void Raycaster::write(size_t index, double z, const Vector3d& ray, const Vector3d& normal, int label) {
  depth_[index] = static_cast<float>(z);
  labels_[index] = static_cast<uint8_t>(label);
  incidence_[index] = static_cast<float>(std::abs(ray.dot(normal)) / ray.norm());
}

// Screen-space bound of a sphere's image: the projected centre and a radius (pixels) that the
// silhouette does not exceed. The silhouette is the cone of half-angle theta = asin(r / |c|) around
// the direction of c, at angle phi from the optical axis; on the image plane its far edge lies
// f (tan(phi + theta) - tan(phi)) = f sin(theta) / (cos(phi + theta) cos(phi)) from the projected
// centre. Returns false when the sphere is too close to the camera or too far off-axis to bound.
bool Raycaster::sphere_screen_bound(const Vector3d& c, double r, Eigen::Vector2d& centre, double& radius) const {
  const double d = c.norm();
  if (c.z() <= kNearPlaneMm || r >= 0.95 * d) return false;
  const double theta = std::asin(r / d);
  const double phi = std::acos(std::clamp(c.z() / d, -1.0, 1.0));
  if (phi + theta > 1.45) return false;  // ~83 deg: the bound explodes
  centre = Eigen::Vector2d(camera_.fx * c.x() / c.z() + camera_.cx, camera_.fy * c.y() / c.z() + camera_.cy);
  radius = std::max(camera_.fx, camera_.fy) * std::sin(theta) / (std::cos(phi + theta) * std::cos(phi)) + 1.0;
  return true;
}

void Raycaster::draw(const ConeSphere& primitive) {
  const ConeSphereGeometry g(primitive);
  // Screen rectangle: project the 8 corners of the primitive's axis-aligned bounding box.
  const Vector3d lo = (primitive.a.array() - primitive.radius_a).min(primitive.b.array() - primitive.radius_b);
  const Vector3d hi = (primitive.a.array() + primitive.radius_a).max(primitive.b.array() + primitive.radius_b);
  if (hi.z() <= kNearPlaneMm) return;  // entirely behind the camera
  int u0 = 0, u1 = camera_.width - 1, v0 = 0, v1 = camera_.height - 1;
  if (lo.z() > kNearPlaneMm) {
    double umin = std::numeric_limits<double>::infinity(), umax = -umin, vmin = umin, vmax = -umin;
    for (int corner = 0; corner < 8; ++corner) {
      const Vector3d p((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(), (corner & 4) ? hi.z() : lo.z());
      const double u = camera_.fx * p.x() / p.z() + camera_.cx;
      const double v = camera_.fy * p.y() / p.z() + camera_.cy;
      umin = std::min(umin, u);
      umax = std::max(umax, u);
      vmin = std::min(vmin, v);
      vmax = std::max(vmax, v);
    }
    if (umax < 0 || vmax < 0 || umin > camera_.width - 1 || vmin > camera_.height - 1) return;
    u0 = std::max(0, static_cast<int>(std::floor(umin)));
    u1 = std::min(camera_.width - 1, static_cast<int>(std::ceil(umax)));
    v0 = std::max(0, static_cast<int>(std::floor(vmin)));
    v1 = std::min(camera_.height - 1, static_cast<int>(std::ceil(vmax)));
  }
  // Tighter 2D cull inside the rectangle: the image of the hull of two spheres lies in the 2D hull
  // of their screen bounds, hence within max(R_a, R_b) of the projected segment.
  Eigen::Vector2d pa, pb;
  double ra = 0, rb = 0;
  const bool cull2d = sphere_screen_bound(primitive.a, primitive.radius_a, pa, ra) &&
                      sphere_screen_bound(primitive.b, primitive.radius_b, pb, rb);
  const Eigen::Vector2d seg = pb - pa;
  const double seg_len2 = std::max(seg.squaredNorm(), 1e-12);
  const double reach2 = std::max(ra, rb) * std::max(ra, rb);

  const auto nearest_possible = static_cast<float>(lo.z());
  Vector3d normal;
  for (int v = v0; v <= v1; ++v) {
    const size_t row = static_cast<size_t>(v) * static_cast<size_t>(camera_.width);
    for (int u = u0; u <= u1; ++u) {
      const size_t index = row + static_cast<size_t>(u);
      if (depth_[index] <= nearest_possible) continue;  // early z rejection
      if (cull2d) {
        const Eigen::Vector2d w(u - pa.x(), v - pa.y());
        const double s = std::clamp(w.dot(seg) / seg_len2, 0.0, 1.0);
        if ((w - s * seg).squaredNorm() > reach2) continue;
      }
      const Vector3d ray(ray_x_[static_cast<size_t>(u)], ray_y_[static_cast<size_t>(v)], 1.0);
      const double t = g.intersect(ray, normal);
      if (t < depth_[index]) write(index, t, ray, normal, primitive.label);
    }
  }
}

void Raycaster::draw(const PlanePatch& plane) {
  // Ray t (x, y, 1) meets n.p = n.o at t = n.o / (n.ray); local coordinates along axis_u and
  // axis_v are t (axis.ray) - axis.o.
  const double offset = plane.normal.dot(plane.origin);
  const double ou = plane.axis_u.dot(plane.origin);
  const double ov = plane.axis_v.dot(plane.origin);
  const Vector3d& n = plane.normal;
  const Vector3d& au = plane.axis_u;
  const Vector3d& av = plane.axis_v;
  // A bounded patch in front of the camera covers only the screen rectangle of its corners.
  int u0 = 0, u1 = camera_.width - 1, v0 = 0, v1 = camera_.height - 1;
  if (plane.half_u > 0 && plane.half_v > 0) {
    double umin = std::numeric_limits<double>::infinity(), umax = -umin, vmin = umin, vmax = -umin;
    bool in_front = true;
    for (const double su : {-1.0, 1.0}) {
      for (const double sv : {-1.0, 1.0}) {
        const Vector3d p = plane.origin + su * plane.half_u * au + sv * plane.half_v * av;
        in_front = in_front && p.z() > kNearPlaneMm;
        umin = std::min(umin, camera_.fx * p.x() / p.z() + camera_.cx);
        umax = std::max(umax, camera_.fx * p.x() / p.z() + camera_.cx);
        vmin = std::min(vmin, camera_.fy * p.y() / p.z() + camera_.cy);
        vmax = std::max(vmax, camera_.fy * p.y() / p.z() + camera_.cy);
      }
    }
    if (in_front) {
      if (umax < 0 || vmax < 0 || umin > camera_.width - 1 || vmin > camera_.height - 1) return;
      u0 = std::max(0, static_cast<int>(std::floor(umin)));
      u1 = std::min(camera_.width - 1, static_cast<int>(std::ceil(umax)));
      v0 = std::max(0, static_cast<int>(std::floor(vmin)));
      v1 = std::min(camera_.height - 1, static_cast<int>(std::ceil(vmax)));
    }
  }
  for (int v = v0; v <= v1; ++v) {
    const size_t row = static_cast<size_t>(v) * static_cast<size_t>(camera_.width);
    const double y = ray_y_[static_cast<size_t>(v)];
    const double n_row = n.y() * y + n.z();
    const double u_row = au.y() * y + au.z();
    const double v_row = av.y() * y + av.z();
    for (int u = u0; u <= u1; ++u) {
      const double x = ray_x_[static_cast<size_t>(u)];
      const double denom = n.x() * x + n_row;
      if (std::abs(denom) < 1e-9) continue;
      const double t = offset / denom;
      const size_t index = row + static_cast<size_t>(u);
      if (t <= kNearPlaneMm || t >= depth_[index]) continue;
      if (plane.half_u > 0 && std::abs(t * (au.x() * x + u_row) - ou) > plane.half_u) continue;
      if (plane.half_v > 0 && std::abs(t * (av.x() * x + v_row) - ov) > plane.half_v) continue;
      depth_[index] = static_cast<float>(t);
      labels_[index] = static_cast<uint8_t>(plane.label);
      incidence_[index] = static_cast<float>(std::abs(denom) / std::sqrt(x * x + y * y + 1.0));
    }
  }
}

}  // namespace handtrack::synth
