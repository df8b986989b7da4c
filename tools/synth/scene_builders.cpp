// Scene layouts: an EuRoC-like room, a corridor ring for loop closure, a KITTI-like city block, and a
// marker wall for geometry tests. World frame: z up, metres.
#include "tools/synth/scene_builders.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace heslam::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Photographs (Debian opencv-doc examples) used as wall, facade and box textures.
const char* const kPhotos[] = {
    "building.jpg",     "graf1.png",        "leuvenA.jpg", "aero1.jpg",        "baboon.jpg",   "fruits.jpg",
    "home.jpg",         "box_in_scene.png", "stuff.jpg",   "starry_night.jpg", "board.jpg",    "orange.jpg",
    "rubberwhale1.png", "basketball1.png",  "messi5.jpg",  "butterfly.jpg",    "smarties.png", "apple.jpg",
    "graf3.png",        "leuvenB.jpg",      "aero3.jpg",   "blox.jpg"};
constexpr int kNumPhotos = sizeof(kPhotos) / sizeof(kPhotos[0]);
// Markers hang this far in front of their wall so the two planes never fight for a pixel.
constexpr double kMarkerStandoffM = 0.01;
// Fixed layout seed: scenes are the same for every sequence seed (only the path varies).
constexpr std::uint64_t kLayoutSeed = 20240601;
// Street buildings: depth from the facade back, and the narrowest building placed at a row's end.
constexpr double kBuildingDepthM = 10.0;
constexpr double kMinBuildingWidthM = 4.0;

struct Textures {
  int photo0 = 0;  // first photo index; photos are consecutive
  int concrete = 0, plaster = 0, tiles = 0, bricks = 0, asphalt = 0;
  int photo(int k) const { return photo0 + ((k % kNumPhotos) + kNumPhotos) % kNumPhotos; }
};

Textures add_textures(Scene& scene, const Preset& preset) {
  Textures t;
  const int size = preset.texture_size_px;
  t.photo0 = static_cast<int>(scene.textures.size());
  for (const char* name : kPhotos) scene.add_texture(load_photo_texture(preset.photo_dir, name, size));
  t.concrete = scene.add_texture(make_procedural_texture(ProceduralKind::kConcrete, kLayoutSeed, size));
  t.plaster = scene.add_texture(make_procedural_texture(ProceduralKind::kPlaster, kLayoutSeed, size));
  t.tiles = scene.add_texture(make_procedural_texture(ProceduralKind::kTiles, kLayoutSeed, size));
  t.bricks = scene.add_texture(make_procedural_texture(ProceduralKind::kBricks, kLayoutSeed, size));
  t.asphalt = scene.add_texture(make_procedural_texture(ProceduralKind::kAsphalt, kLayoutSeed, size));
  return t;
}

// A horizontal rectangle at height z, visible from above (up = true) or below.
void add_horizontal(Scene& s, double x0, double y0, double x1, double y1, double z, bool up, int texture,
                    double texel_m, float albedo) {
  Quad q;
  q.origin_w = {x0, up ? y0 : y1, z};
  q.axis_u_w = Eigen::Vector3d::UnitX();
  q.axis_v_w = Eigen::Vector3d(0.0, up ? 1.0 : -1.0, 0.0);
  q.size_u_m = x1 - x0;
  q.size_v_m = y1 - y0;
  q.texture = texture;
  q.texel_m = texel_m;
  s.add_quad(q, albedo);
}

// A vertical wall from a to b (floor points), height h, seen from the left of a->b, split into
// panels of about panel_m, each with the next texture from `pick`.
template <typename Pick>
void add_wall(Scene& s, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double h, double panel_m, Pick pick,
              double texel_m, float albedo) {
  const Eigen::Vector3d along = b - a;
  const int panels = std::max(1, static_cast<int>(std::round(along.norm() / panel_m)));
  for (int i = 0; i < panels; ++i) {
    Quad q;
    // Seen from the left of a->b: u runs b->a so the picture is not mirrored for that viewer.
    const Eigen::Vector3d p_end = a + along * (static_cast<double>(i + 1) / panels);
    q.origin_w = p_end + h * Eigen::Vector3d::UnitZ();
    q.axis_u_w = -along.normalized();
    q.axis_v_w = -Eigen::Vector3d::UnitZ();
    q.size_u_m = along.norm() / panels;
    q.size_v_m = h;
    q.texture = pick(i);
    q.texel_m = texel_m;
    q.s0_texels = 37.0 * i;
    s.add_quad(q, albedo);
  }
}

// A marker on the wall from a to b (seen from its left), centred at fraction f along it, height z.
void add_wall_marker(Scene& s, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double f, double z, double cell_m) {
  const Eigen::Vector3d along = (b - a).normalized();
  const Eigen::Vector3d left(-along.y(), along.x(), 0.0);
  const Eigen::Vector3d center = a + f * (b - a) + z * Eigen::Vector3d::UnitZ() + kMarkerStandoffM * left;
  s.add_checker_marker(center, -along, -Eigen::Vector3d::UnitZ(), cell_m, CheckerLayout{});
}

// Points every spacing_m along a polyline (the vertices themselves are cut, as a walker would).
std::vector<Eigen::Vector3d> resample_polyline(const std::vector<Eigen::Vector3d>& poly, double spacing_m) {
  std::vector<Eigen::Vector3d> out{poly.front()};
  double carry = 0.0;  // distance already walked since the last emitted point
  for (std::size_t i = 1; i < poly.size(); ++i) {
    const Eigen::Vector3d seg = poly[i] - poly[i - 1];
    const double len = seg.norm();
    double at = spacing_m - carry;
    while (at <= len) {
      out.push_back(poly[i - 1] + seg * (at / len));
      at += spacing_m;
    }
    carry = len - (at - spacing_m);
  }
  return out;
}

BuiltScene build_room(const Preset& preset) {
  BuiltScene out;
  Scene& s = out.scene;
  const Textures t = add_textures(s, preset);
  const double hx = 5.0, hy = 4.0, h = 3.0;
  add_horizontal(s, -hx, -hy, hx, hy, 0.0, true, t.concrete, 0.008, 1.0f);
  add_horizontal(s, -hx, -hy, hx, hy, h, false, t.plaster, 0.01, 1.0f);
  const Eigen::Vector3d c00(-hx, -hy, 0), c10(hx, -hy, 0), c11(hx, hy, 0), c01(-hx, hy, 0);
  int k = 0;
  auto photos = [&](int) { return t.photo(k++); };
  // Walls seen from inside: walk the room counter-clockwise so the inside is on the left.
  add_wall(s, c00, c10, h, 2.5, photos, 0.006, 1.0f);
  add_wall(s, c10, c11, h, 2.7, photos, 0.006, 1.0f);
  add_wall(s, c11, c01, h, 2.5, photos, 0.006, 1.0f);
  add_wall(s, c01, c00, h, 2.7, photos, 0.006, 1.0f);
  add_wall_marker(s, c00, c10, 0.3, 1.5, 0.08);
  add_wall_marker(s, c10, c11, 0.6, 1.4, 0.08);
  add_wall_marker(s, c11, c01, 0.55, 1.6, 0.08);
  // Furniture-sized blocks: a central table, cabinets and boxes along the walls.
  s.add_box({0.0, 0.0, 0.0}, {1.4, 0.8, 0.75}, 0.2, {t.bricks, t.photo(4)}, t.photo(10), 0.004, 0.9f, 1);
  s.add_box({0.3, 0.2, 0.75}, {0.4, 0.3, 0.3}, 0.7, {t.photo(5), t.photo(6)}, t.photo(7), 0.0015, 1.0f, 2);
  s.add_box({-4.2, -2.5, 0.0}, {0.9, 1.4, 1.9}, 0.0, {t.photo(8), t.photo(12)}, t.tiles, 0.004, 0.95f, 3);
  s.add_box({4.1, 2.4, 0.0}, {1.0, 1.0, 1.1}, 0.3, {t.photo(13), t.photo(14), t.photo(15)}, t.photo(16), 0.003, 1.0f,
            4);
  s.add_box({3.6, -3.2, 0.0}, {1.6, 0.7, 0.8}, -0.1, {t.photo(17), t.bricks}, t.photo(18), 0.003, 0.9f, 5);
  s.add_box({-3.5, 3.2, 0.0}, {1.2, 0.8, 1.5}, 0.15, {t.photo(19), t.photo(20)}, t.photo(21), 0.003, 1.0f, 6);
  s.add_box({-0.5, 3.4, 0.0}, {0.6, 0.6, 0.6}, 0.6, {t.photo(1), t.photo(2)}, t.photo(3), 0.002, 1.0f, 7);
  s.add_box({0.8, -3.3, 0.0}, {0.7, 0.7, 0.9}, -0.4, {t.photo(9), t.photo(11)}, t.photo(0), 0.002, 1.0f, 8);
  s.add_box({-4.3, 0.6, 0.0}, {0.5, 1.8, 0.9}, 0.0, {t.tiles, t.photo(3)}, t.concrete, 0.003, 0.9f, 9);
  // Nominal path: an ellipse around the table at head height.
  const int n = 12;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    out.path.control_points_w.push_back({2.6 * std::cos(a), 1.9 * std::sin(a), 1.4});
  }
  out.path.closed = true;
  return out;
}

BuiltScene build_corridor_loop(const Preset& preset) {
  BuiltScene out;
  Scene& s = out.scene;
  const Textures t = add_textures(s, preset);
  const double X = 16.0, Y = 10.0, w = 2.4, h = 2.8;
  add_horizontal(s, 0, 0, X, Y, 0.0, true, t.tiles, 0.004, 1.0f);
  add_horizontal(s, 0, 0, X, Y, h, false, t.plaster, 0.008, 1.0f);
  int k = 3;
  auto photos = [&](int i) { return (i % 3 == 2) ? t.bricks : t.photo(k++); };
  // Outer walls seen from inside (counter-clockwise), the inner block's walls seen from outside.
  const Eigen::Vector3d o00(0, 0, 0), o10(X, 0, 0), o11(X, Y, 0), o01(0, Y, 0);
  add_wall(s, o00, o10, h, 2.0, photos, 0.005, 1.0f);
  add_wall(s, o10, o11, h, 2.0, photos, 0.005, 1.0f);
  add_wall(s, o11, o01, h, 2.0, photos, 0.005, 1.0f);
  add_wall(s, o01, o00, h, 2.0, photos, 0.005, 1.0f);
  const Eigen::Vector3d i00(w, w, 0), i10(X - w, w, 0), i11(X - w, Y - w, 0), i01(w, Y - w, 0);
  add_wall(s, i10, i00, h, 2.0, photos, 0.005, 0.95f);
  add_wall(s, i11, i10, h, 2.0, photos, 0.005, 0.95f);
  add_wall(s, i01, i11, h, 2.0, photos, 0.005, 0.95f);
  add_wall(s, i00, i01, h, 2.0, photos, 0.005, 0.95f);
  add_wall_marker(s, o00, o10, 0.5, 1.5, 0.06);
  add_wall_marker(s, o11, o01, 0.4, 1.5, 0.06);
  // Cabinets against the outer walls (0.4 m deep: the corridor stays passable).
  s.add_box({6.0, 0.25, 0}, {1.2, 0.4, 1.0}, 0.0, {t.photo(10), t.photo(11)}, t.photo(12), 0.003, 1.0f, 11);
  s.add_box({15.75, 5.0, 0}, {0.4, 1.6, 1.4}, 0.0, {t.photo(13), t.photo(14)}, t.photo(15), 0.003, 1.0f, 12);
  s.add_box({9.0, 9.75, 0}, {1.0, 0.4, 0.9}, 0.0, {t.photo(16), t.photo(17)}, t.photo(18), 0.003, 1.0f, 13);
  s.add_box({0.25, 4.0, 0}, {0.4, 1.0, 1.7}, 0.0, {t.photo(19), t.photo(20)}, t.photo(21), 0.003, 1.0f, 14);
  s.add_box({12.0, 2.2, 0}, {0.8, 0.3, 0.7}, 0.0, {t.photo(1), t.photo(2)}, t.photo(4), 0.002, 1.0f, 15);
  // Path: round the ring counter-clockwise back past the start, U-turn, and back the other way.
  const double lo = w / 2, xr = X - w / 2, yt = Y - w / 2;
  auto& p = out.path.control_points_w;
  const double z = 1.5;
  // Evenly spaced control points: uneven spacing at corners would make the spline turn sharply.
  const std::vector<Eigen::Vector3d> ring = {{4.0, lo, z}, {xr, lo, z}, {xr, yt, z},
                                             {lo, yt, z},  {lo, lo, z}, {9.0, lo, z}};
  p = resample_polyline(ring, 2.0);
  // U-turn on a 0.75 m circle (dense points keep the spline's radius close to it).
  for (int k = -4; k <= 4; ++k) {
    const double a = k * kPi / 8;
    p.push_back({11.0 + 0.75 * std::cos(a), 1.2 + 0.75 * std::sin(a), z});
  }
  for (double x = 8.6; x >= 2.0; x -= 2.0) p.push_back({x, 1.7, z});
  out.path.closed = false;
  return out;
}

// Streets lined with buildings, sidewalks, parked cars and lane dashes; shared by `street` (one block
// and a ring of facades round it) and `town` (a grid of blocks). Roads are given by their centre lines.
class CityBuilder {
 public:
  CityBuilder(Scene& scene, const Textures& textures, double setback_m, double curb_m, double no_parking_m)
      : s_(scene), t_(textures), setback_(setback_m), curb_(curb_m), no_parking_(no_parking_m), rng_(kLayoutSeed) {}

  // Buildings on one side of the road from a to b: the left side (sign +1, a block's edge walked
  // counter-clockwise) or the right side (sign -1, the outer ring facing into the town). They stop
  // where the crossing streets begin, and each row fills the corner square at its start (the
  // previous row stops short of it: no two facades share a plane). Rows from -setback to past
  // length + setback would stand across the crossing roads, and the street drive would start 8 m in
  // front of a facade it then drives through.
  void building_row(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double sign) {
    const Eigen::Vector2d dir = (b - a).normalized();
    const Eigen::Vector2d left(-dir.y(), dir.x());
    const double length = (b - a).norm();
    const bool inner = sign > 0;
    const double row_start = inner ? setback_ : -setback_ - kBuildingDepthM;
    const double row_end = inner ? length - setback_ - kBuildingDepthM : length + setback_;
    double along = row_start;
    while (along < row_end - kMinBuildingWidthM) {
      const double width = std::min(uniform(10.0, 22.0), row_end - along);
      const double height = uniform(7.0, 20.0);
      const Eigen::Vector2d c = a + dir * (along + width / 2) + left * sign * (setback_ + kBuildingDepthM / 2);
      const int facade = (photo_ % 3 == 1) ? t_.bricks : t_.photo(photo_);
      s_.add_box({c.x(), c.y(), 0.0}, {width, kBuildingDepthM, height}, std::atan2(dir.y(), dir.x()),
                 {facade, t_.photo(photo_ + 5)}, t_.concrete, 0.035, 1.0f, static_cast<std::uint64_t>(photo_) + 100);
      ++photo_;
      along += width + uniform(0.0, 3.0);
    }
  }

  // Sidewalk strip in front of that row. Inner: from curb to curb of the crossing streets; outer:
  // round the outer corner it starts at.
  void sidewalk(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double sign) {
    const Eigen::Vector2d dir = (b - a).normalized();
    const Eigen::Vector2d left(-dir.y(), dir.x());
    const double length = (b - a).norm();
    const double walk_start = sign > 0 ? curb_ : -setback_;
    const double walk_end = sign > 0 ? length - curb_ : length + curb_;
    const Eigen::Vector2d start = a + dir * walk_start + left * sign * curb_;
    Quad walk;
    walk.origin_w = {start.x(), start.y(), 0.02};
    walk.axis_u_w = {dir.x(), dir.y(), 0.0};
    walk.axis_v_w = Eigen::Vector3d(left.x(), left.y(), 0.0) * sign;
    walk.size_u_m = walk_end - walk_start;
    walk.size_v_m = setback_ - curb_;
    walk.texture = t_.tiles;
    walk.texel_m = 0.006;
    s_.add_quad(walk, 1.0f);
  }

  // Parked cars along the left curb of a -> b, none within no_parking_m of the junctions.
  void parked_cars(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d dir = (b - a).normalized();
    const Eigen::Vector2d left(-dir.y(), dir.x());
    const double length = (b - a).norm();
    for (double along = no_parking_; along < length - no_parking_; along += uniform(5.0, 12.0)) {
      if (uniform(0, 1) < 0.45) continue;
      const Eigen::Vector2d c = a + dir * along + left * (curb_ - 1.1);
      s_.add_box({c.x(), c.y(), 0.0}, {4.2, 1.8, 1.45}, std::atan2(dir.y(), dir.x()),
                 {t_.photo(photo_), t_.photo(photo_ + 7)}, t_.photo(photo_ + 3), 0.004, 0.8f,
                 static_cast<std::uint64_t>(photo_) + 500);
      ++photo_;
      along += 4.2;
    }
  }

  // Dashed lane marking along the centre line from a to b.
  void lane_dashes(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d dir = (b - a).normalized();
    const Eigen::Vector2d left(-dir.y(), dir.x());
    const double length = (b - a).norm();
    for (double along = 0.0; along + 3.0 < length; along += 9.0) {
      Quad dash;
      const Eigen::Vector2d p0 = a + dir * along + left * 0.075;
      dash.origin_w = {p0.x(), p0.y(), 0.01};
      dash.axis_u_w = {dir.x(), dir.y(), 0.0};
      dash.axis_v_w = {-left.x(), -left.y(), 0.0};
      dash.size_u_m = 3.0;
      dash.size_v_m = 0.15;
      dash.texture = t_.plaster;
      dash.texel_m = 0.01;
      s_.add_quad(dash, 1.1f);
    }
  }

 private:
  double uniform(double lo, double hi) { return lo + (hi - lo) * static_cast<double>(rng_() >> 11) * 0x1.0p-53; }

  Scene& s_;
  const Textures& t_;
  double setback_;     // centre line to facades
  double curb_;        // centre line to curb (parked cars stand beyond it)
  double no_parking_;  // junction centre to the first / last parking place
  std::mt19937_64 rng_;
  int photo_ = 0;
};

// KITTI-like lighting and sky over asphalt covering [x0, x1] x [y0, y1].
void city_ground_and_light(Scene& s, const Textures& t, double x0, double y0, double x1, double y1) {
  s.sky_radiance = 0.95f;
  s.ambient = 0.6f;
  s.diffuse = 0.4f;
  s.light_dir_w = Eigen::Vector3d(0.5, -0.3, 0.8).normalized();
  add_horizontal(s, x0, y0, x1, y1, 0.0, true, t.asphalt, 0.02, 1.0f);
}

// Control points of a drive through the road junctions `route` on the right-hand lane: every 10 m
// of each leg from 10 m after its start junction to 10 m before its end junction (the spline rounds
// the corners in between), at KITTI's camera height.
void drive_through(const std::vector<Eigen::Vector2d>& route, std::vector<Eigen::Vector3d>& control_points_w) {
  constexpr double kRightLaneM = 1.8;
  constexpr double kCameraHeightM = 1.65;
  for (std::size_t leg = 0; leg + 1 < route.size(); ++leg) {
    const Eigen::Vector2d dir = (route[leg + 1] - route[leg]).normalized();
    const Eigen::Vector2d right(dir.y(), -dir.x());
    const double length = (route[leg + 1] - route[leg]).norm();
    for (double along = 10.0; along <= length - 10.0; along += 10.0) {
      const Eigen::Vector2d q = route[leg] + dir * along + right * kRightLaneM;
      control_points_w.push_back({q.x(), q.y(), kCameraHeightM});
    }
  }
}

BuiltScene build_street(const Preset& preset) {
  BuiltScene out;
  Scene& s = out.scene;
  const Textures t = add_textures(s, preset);
  const double X = 160.0, Y = 100.0;  // road centre line rectangle
  city_ground_and_light(s, t, -40, -40, X + 40, Y + 40);
  CityBuilder city(s, t, /*setback_m=*/7.5, /*curb_m=*/4.5, /*no_parking_m=*/15.0);
  // Along each of the four sides (counter-clockwise): the block's row, the outer ring's row, the
  // block's parked cars, the centre line.
  const Eigen::Vector2d corners[5] = {{0, 0}, {X, 0}, {X, Y}, {0, Y}, {0, 0}};
  for (int side = 0; side < 4; ++side) {
    const Eigen::Vector2d& a = corners[side];
    const Eigen::Vector2d& b = corners[side + 1];
    for (const double sign : {1.0, -1.0}) {
      city.building_row(a, b, sign);
      city.sidewalk(a, b, sign);
    }
    city.parked_cars(a, b);
    city.lane_dashes(a, b);
  }
  // Path: once round the block counter-clockwise on the right-hand lane, then 130 m of the first side again.
  drive_through({{0, 0}, {X, 0}, {X, Y}, {0, Y}, {0, 0}, {140, 0}}, out.path.control_points_w);
  out.path.closed = false;
  return out;
}

BuiltScene build_town(const Preset& preset) {
  BuiltScene out;
  Scene& s = out.scene;
  const Textures t = add_textures(s, preset);
  // Road centre lines: three streets each way; four blocks of 100 / 80 x 80 / 70 m between them.
  const double xs[3] = {0.0, 100.0, 180.0};
  const double ys[3] = {0.0, 80.0, 150.0};
  city_ground_and_light(s, t, -40, -40, xs[2] + 40, ys[2] + 40);
  // Wider streets than `street` (the drive passes parked cars on its own side too), and no parking
  // where a right turn's path cuts towards the curb.
  CityBuilder city(s, t, /*setback_m=*/9.0, /*curb_m=*/5.5, /*no_parking_m=*/22.0);
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      const Eigen::Vector2d c[5] = {
          {xs[i], ys[j]}, {xs[i + 1], ys[j]}, {xs[i + 1], ys[j + 1]}, {xs[i], ys[j + 1]}, {xs[i], ys[j]}};
      for (int edge = 0; edge < 4; ++edge) {
        city.building_row(c[edge], c[edge + 1], 1.0);
        city.sidewalk(c[edge], c[edge + 1], 1.0);
        city.parked_cars(c[edge], c[edge + 1]);
      }
    }
  }
  // The outer ring of facades looks into the town from beyond the boundary streets (continuous past
  // the T-junctions, where the crossing street ends at it).
  const Eigen::Vector2d boundary[5] = {{xs[0], ys[0]}, {xs[2], ys[0]}, {xs[2], ys[2]}, {xs[0], ys[2]}, {xs[0], ys[0]}};
  for (int side = 0; side < 4; ++side) {
    city.building_row(boundary[side], boundary[side + 1], -1.0);
    city.sidewalk(boundary[side], boundary[side + 1], -1.0);
  }
  for (const double y : ys) city.lane_dashes({xs[0], y}, {xs[2], y});
  for (const double x : xs) city.lane_dashes({x, ys[0]}, {x, ys[2]});
  // Path: east, left at the T-junction, north to the crossroads (the preset stops there), right,
  // left, left, left, straight over the crossroads, right at the T-junction, and back west.
  drive_through({{xs[0], ys[0]},
                 {xs[1], ys[0]},
                 {xs[1], ys[1]},
                 {xs[2], ys[1]},
                 {xs[2], ys[2]},
                 {xs[1], ys[2]},
                 {xs[1], ys[0]},
                 {xs[0], ys[0]}},
                out.path.control_points_w);
  out.path.closed = false;
  return out;
}

BuiltScene build_marker_wall(const Preset& preset) {
  BuiltScene out;
  Scene& s = out.scene;
  const Textures t = add_textures(s, preset);
  // A textured wall facing -x at x = 4 with a 3 x 2 grid of markers, a floor, and one box.
  add_horizontal(s, -2, -6, 4, 6, 0.0, true, t.concrete, 0.008, 1.0f);
  const Eigen::Vector3d a(4, -6, 0), b(4, 6, 0);
  add_wall(
      s, a, b, 4.0, 3.0, [&](int i) { return t.photo(i); }, 0.006, 1.0f);
  for (int row = 0; row < 2; ++row)
    for (int col = 0; col < 3; ++col) add_wall_marker(s, a, b, 0.4 + 0.1 * col, 1.0 + 1.0 * row, 0.05);
  s.add_box({3.2, -2.7, 0}, {0.6, 0.6, 0.8}, 0.3, {t.photo(5), t.photo(6)}, t.photo(7), 0.002, 1.0f, 1);
  // Sideways slide in front of the wall (a preset turns the camera to face it with yaw_offset_deg).
  for (int i = 0; i < 6; ++i) out.path.control_points_w.push_back({2.0, -1.5 + 0.6 * i, 1.5});
  out.path.closed = false;
  return out;
}

}  // namespace

BuiltScene build_scene(const Preset& preset) {
  switch (preset.scene) {
    case SceneKind::kRoom: return build_room(preset);
    case SceneKind::kCorridorLoop: return build_corridor_loop(preset);
    case SceneKind::kStreet: return build_street(preset);
    case SceneKind::kTown: return build_town(preset);
    case SceneKind::kMarkerWall: return build_marker_wall(preset);
  }
  return build_room(preset);
}

}  // namespace heslam::synth
