// The apartment generator: integer layout on a 5 cm grid, then walls / floors / ceilings, then
// furniture room by room on a 5 cm occupancy grid with a navigability check per placement.
#include "sim/apartment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <queue>
#include <tuple>

#include "io/mesh_io.h"
#include "sim/scene_loader.h"

namespace voxplan {

namespace {

using Color = std::array<uint8_t, 3>;
using V3 = Eigen::Vector3f;

constexpr double kUnit = 0.05;  // layout grid, metres
constexpr double kPi = 3.14159265358979323846;
float M(int u) { return float(double(u) * kUnit); }

// SplitMix64: the same stream on every platform and standard library.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed ^ 0x5DEECE66DA3F1C2Bull) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double Uniform() { return double(Next() >> 11) * (1.0 / 9007199254740992.0); }
  double Uniform(double a, double b) { return a + (b - a) * Uniform(); }
  int Int(int lo, int hi) {  // inclusive
    if (hi <= lo) return lo;
    return lo + int(Next() % uint64_t(hi - lo + 1));
  }
  bool Chance(double p) { return Uniform() < p; }
  template <typename T>
  void Shuffle(std::vector<T>* v) {
    for (size_t i = v->size(); i > 1; --i) std::swap((*v)[i - 1], (*v)[Next() % i]);
  }

 private:
  uint64_t state_;
};

Color Jitter(Color c, Rng& rng, int amount = 12) {
  for (auto& v : c) v = uint8_t(std::clamp(int(v) + rng.Int(-amount, amount), 0, 255));
  return c;
}

// ---------------------------------------------------------------------------------------------
// Layout (integer units of 5 cm).

struct RectU {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

struct DoorU {
  bool along_x = true;  // the wall runs along x; the opening is an x interval
  int o0 = 0, o1 = 0;   // opening along the wall
  int t0 = 0, t1 = 0;   // the wall's thickness range (y for along_x walls)
  int height = 42;      // 2.1 m
  bool closed = false;  // the entrance: a door slab fills the opening
  int room_a = -1, room_b = -1;
  int floor_room = -1;  // whose floor covers the threshold
};

struct WallU {
  bool along_x = true;
  int a0 = 0, a1 = 0;  // extent along the wall
  int t0 = 0, t1 = 0;  // thickness range
  std::vector<int> doors;
};

struct RoomU {
  std::string name, type;
  RectU r;
};

struct Layout {
  int W = 0, D = 0, H = 52;
  std::vector<RoomU> rooms;
  std::vector<WallU> walls;
  std::vector<DoorU> doors;
};

int Snap(double metres) { return int(std::lround(metres / kUnit)); }

Layout MakeLayout(ApartmentSize size, Rng& rng) {
  float lo_m2, hi_m2;
  ApartmentAreaRange(size, &lo_m2, &hi_m2);
  const double margin = 0.05 * (hi_m2 - lo_m2);
  const double area = rng.Uniform(lo_m2 + margin, hi_m2 - margin);
  constexpr int te = 3, ti = 2, kMinStrip = 48;
  Layout L;
  L.H = 50 + rng.Int(0, 4);  // 2.50 .. 2.70 m
  const int cw = rng.Int(24, 30);
  const double d_min_m = (2 * te + 2 * ti + cw + 2 * kMinStrip) * kUnit;
  double dlo = size == ApartmentSize::kS ? 6.6 : size == ApartmentSize::kM ? 7.6 : 9.6;
  double dhi = size == ApartmentSize::kS ? 8.0 : size == ApartmentSize::kM ? 10.4 : 13.4;
  dlo = std::max({dlo, d_min_m, std::sqrt(area / 2.3)});
  dhi = std::max(dlo, std::min(dhi, std::sqrt(area / 1.15)));
  L.D = Snap(rng.Uniform(dlo, dhi));
  L.W = Snap(area / (L.D * kUnit));
  const int W = L.W, D = L.D;

  // y: south strip, corridor, north strip.
  const int avail = D - 2 * te - 2 * ti - cw;
  int ds = int(std::lround(avail * rng.Uniform(0.42, 0.58)));
  ds = std::clamp(ds, kMinStrip, avail - kMinStrip);
  const int yc0 = te + ds + ti, yc1 = yc0 + cw;
  const int yn0 = yc1 + ti, yn1 = D - te;
  // x: west part (strips + corridor), separator wall, living block.
  int lw = int(std::lround(W * rng.Uniform(0.26, 0.34)));
  lw = std::max(lw, 66);
  const int xw = W - te - lw - ti;  // separator wall at [xw, xw + ti]
  const int xe0 = xw + ti, xe1 = W - te;

  // The room program.
  const bool split_east =
      size != ApartmentSize::kS && lw * (D - 2 * te) * kUnit * kUnit > 38.0 && rng.Chance(0.6);
  const bool kitchen_east = split_east && rng.Chance(0.5);
  std::vector<std::string> extras = {"bedroom", "bedroom", "study", "wc", "storage", "bedroom"};
  if (size == ApartmentSize::kL)
    extras = {"bedroom", "bedroom", "bathroom", "study", "bedroom",
              "wc",      "storage", "bedroom",  "study"};
  if (size == ApartmentSize::kS) extras = {"bedroom", "study", "storage"};

  auto weight = [](const std::string& type) {
    if (type == "wc" || type == "storage") return 0.55;
    if (type == "bathroom") return 0.75;
    if (type == "kitchen") return 1.1;
    if (type == "study") return 0.9;
    return 1.2;
  };
  auto min_width = [](const std::string& type) {
    if (type == "wc" || type == "storage") return 32;
    if (type == "bathroom") return 38;
    return 50;
  };
  const int strip_len = xw - te;
  auto rooms_in_strip = [&](double per_room_m) {
    return std::clamp(int(std::lround(strip_len * kUnit / per_room_m)), 1, 6);
  };
  int n_north = rooms_in_strip(rng.Uniform(3.3, 4.3));
  int n_south = rooms_in_strip(rng.Uniform(3.3, 4.3));
  // At least a bathroom and a bedroom, plus the kitchen when it is not in the living block.
  const int min_slots = kitchen_east ? 2 : 3;
  if (n_north + n_south < min_slots) n_south = min_slots - n_north;

  // Slots: north strip west -> east, then south strip west -> east. The kitchen (unless in the
  // living block) takes the north slot next to the living block.
  std::vector<std::string> program;
  for (int attempt = 0;; ++attempt) {
    const int slots = n_north + n_south;
    std::vector<std::string> names = {"bathroom", "bedroom"};
    for (size_t i = 0; names.size() + (kitchen_east ? 0 : 1) < size_t(slots) && i < extras.size();
         ++i)
      names.push_back(extras[i]);
    while (names.size() + (kitchen_east ? 0 : 1) < size_t(slots)) names.push_back("bedroom");
    rng.Shuffle(&names);
    program.assign(slots, "");
    size_t k = 0;
    for (int s = 0; s < slots; ++s) {
      if (!kitchen_east && s == n_north - 1)
        program[s] = "kitchen";
      else
        program[s] = names[k++];
    }
    // Widths per strip; shrink the strip's room count while a room would be too narrow.
    bool ok = true;
    for (int strip = 0; strip < 2 && ok; ++strip) {
      const int first = strip == 0 ? 0 : n_north, n = strip == 0 ? n_north : n_south;
      double wsum = 0.0;
      for (int i = 0; i < n; ++i) wsum += weight(program[first + i]);
      const int usable = strip_len - (n - 1) * ti;
      for (int i = 0; i < n; ++i)
        if (usable * weight(program[first + i]) / wsum < min_width(program[first + i]) + 2)
          ok = false;
      if (!ok) {
        if (n_north + n_south <= min_slots) {
          ok = true;  // keep the program; rooms are narrower than wished
        } else if (strip == 0 && n_north > 1) {
          --n_north;
        } else if (n_south > 1) {
          --n_south;
        } else if (n_north > 1) {
          --n_north;
        }
      }
    }
    if (ok || attempt > 20) break;
  }

  std::map<std::string, int> counts;
  auto add_room = [&](const std::string& type, RectU r) {
    RoomU room;
    room.type = type;
    room.r = r;
    L.rooms.push_back(room);
    ++counts[type];
    return int(L.rooms.size()) - 1;
  };
  auto add_door = [&](DoorU d) {
    L.doors.push_back(d);
    return int(L.doors.size()) - 1;
  };

  // Walls with fixed extents; doors are attached below.
  auto add_wall = [&](bool along_x, int a0, int a1, int t0, int t1) {
    L.walls.push_back({along_x, a0, a1, t0, t1, {}});
    return int(L.walls.size()) - 1;
  };
  add_wall(true, 0, W, 0, te);      // south exterior
  add_wall(true, 0, W, D - te, D);  // north exterior
  const int w_west = add_wall(false, te, D - te, 0, te);
  add_wall(false, te, D - te, W - te, W);  // east exterior
  const int w_sep = add_wall(false, te, D - te, xw, xw + ti);
  const int w_cs = add_wall(true, te, xw, yc0 - ti, yc0);  // corridor south wall
  const int w_cn = add_wall(true, te, xw, yc1, yc1 + ti);  // corridor north wall

  const int corridor = add_room("corridor", {te, yc0, xw, yc1});

  // Strip rooms.
  int kitchen_room = -1;
  for (int strip = 0; strip < 2; ++strip) {
    const int first = strip == 0 ? 0 : n_north, n = strip == 0 ? n_north : n_south;
    const int y0 = strip == 0 ? yn0 : te, y1 = strip == 0 ? yn1 : yc0 - ti;
    double wsum = 0.0;
    std::vector<double> wts;
    for (int i = 0; i < n; ++i) {
      wts.push_back(weight(program[first + i]) * rng.Uniform(0.92, 1.08));
      wsum += wts.back();
    }
    const int usable = strip_len - (n - 1) * ti;
    int x = te, used = 0;
    for (int i = 0; i < n; ++i) {
      const int w = i == n - 1 ? usable - used : int(std::floor(usable * wts[i] / wsum));
      used += w;
      const std::string& type = program[first + i];
      const int room = add_room(type, {x, y0, x + w, y1});
      if (type == "kitchen") kitchen_room = room;
      // Door onto the corridor.
      DoorU d;
      d.along_x = true;
      const int dw = (type == "bathroom" || type == "wc" || type == "storage") ? 16 : 18;
      const int lo = x + 3, hi = std::max(lo, x + w - 3 - dw);
      d.o0 = rng.Int(lo, hi);
      d.o1 = d.o0 + dw;
      d.t0 = strip == 0 ? yc1 : yc0 - ti;
      d.t1 = d.t0 + ti;
      d.room_a = room;
      d.room_b = corridor;
      d.floor_room = room;
      L.walls[strip == 0 ? w_cn : w_cs].doors.push_back(add_door(d));
      if (i + 1 < n) add_wall(false, y0, y1, x + w, x + w + ti);
      x += w + ti;
    }
  }

  // The living block, maybe split along the corridor's north or south wall line.
  int living = -1, east_other = -1;
  if (split_east) {
    const bool other_north = rng.Chance(0.5);
    const std::string other_type = kitchen_east ? "kitchen" : "dining";
    if (other_north) {
      living = add_room("living", {xe0, te, xe1, yc1});
      east_other = add_room(other_type, {xe0, yc1 + ti, xe1, D - te});
    } else {
      living = add_room("living", {xe0, yc0, xe1, D - te});
      east_other = add_room(other_type, {xe0, te, xe1, yc0 - ti});
    }
    if (kitchen_east) kitchen_room = east_other;
    const int ys = other_north ? yc1 : yc0 - ti;
    const int w_split = add_wall(true, xe0, xe1, ys, ys + ti);
    DoorU d;
    d.along_x = true;
    const int dw = 24;
    d.o0 = rng.Int(xe0 + 3, std::max(xe0 + 3, xe1 - 3 - dw));
    d.o1 = d.o0 + dw;
    d.t0 = ys;
    d.t1 = ys + ti;
    d.room_a = east_other;
    d.room_b = living;
    d.floor_room = east_other;
    L.walls[w_split].doors.push_back(add_door(d));
  } else {
    living = add_room("living", {xe0, te, xe1, D - te});
  }
  // Corridor -> living block: the corridor's full width.
  {
    DoorU d;
    d.along_x = false;
    d.o0 = yc0;
    d.o1 = yc1;
    d.t0 = xw;
    d.t1 = xw + ti;
    d.room_a = corridor;
    d.room_b = living;
    d.floor_room = corridor;
    L.walls[w_sep].doors.push_back(add_door(d));
  }
  // Kitchen in the north strip next to the living block: a second door into the block.
  if (kitchen_room >= 0 && L.rooms[kitchen_room].r.x1 == xw) {
    const RectU& k = L.rooms[kitchen_room].r;
    int east_room = living;
    if (east_other >= 0 && L.rooms[east_other].r.y0 <= k.y0 && L.rooms[east_other].r.y1 >= k.y1)
      east_room = east_other;
    DoorU d;
    d.along_x = false;
    const int dw = 18;
    d.o0 = rng.Int(k.y0 + 3, std::max(k.y0 + 3, k.y1 - 3 - dw));
    d.o1 = d.o0 + dw;
    d.t0 = xw;
    d.t1 = xw + ti;
    d.room_a = kitchen_room;
    d.room_b = east_room;
    d.floor_room = kitchen_room;
    L.walls[w_sep].doors.push_back(add_door(d));
  }
  // The entrance: a closed door in the west wall at the corridor.
  {
    DoorU d;
    d.along_x = false;
    const int dw = std::min(20, cw - 2);
    d.o0 = rng.Int(yc0 + 1, yc1 - 1 - dw);
    d.o1 = d.o0 + dw;
    d.t0 = 0;
    d.t1 = te;
    d.closed = true;
    d.room_a = corridor;
    d.floor_room = corridor;
    L.walls[w_west].doors.push_back(add_door(d));
  }
  // Names: bedroom_1, bedroom_2, ... where a type repeats.
  std::map<std::string, int> seen;
  for (RoomU& room : L.rooms)
    room.name =
        counts[room.type] > 1 ? room.type + "_" + std::to_string(++seen[room.type]) : room.type;
  return L;
}

// ---------------------------------------------------------------------------------------------
// Geometry.

struct Part {
  bool cylinder = false;
  V3 lo, hi;  // local box; a cylinder is inscribed in its xy footprint
  Color color{};
};

struct PreparedMesh {
  Mesh mesh;             // native (Z-up after the Y-up read), centred in xy, z from 0
  int quarter = 0;       // native -> local: turns the model's back to +y
  V3 size = V3::Zero();  // native extents
};

struct Item {
  std::string cls, model;     // empty cls: a group, no instance of its own
  float w = 0, d = 0, h = 0;  // local footprint x in [-w/2, w/2], y in [-d/2, d/2] (back +y)
  std::vector<Part> parts;
  const PreparedMesh* mesh = nullptr;
  bool walkable = false;  // below the robot's band (rugs): not an obstacle
  struct Child;
  std::vector<Child> children;
};
struct Item::Child {
  Item item;
  float x = 0, y = 0, z = 0;
  int quarter = 0;
};

Eigen::Vector2f Rot(int q, float x, float y) {
  switch (q & 3) {
    case 0:
      return {x, y};
    case 1:
      return {-y, x};
    case 2:
      return {-x, -y};
    default:
      return {y, -x};
  }
}

class Emitter {
 public:
  explicit Emitter(World* world) : world_(world) {}

  uint32_t NewInstance(const std::string& cls, const std::string& model) {
    Instance inst;
    inst.id = uint32_t(world_->instances.size() + 1);
    inst.class_name = cls;
    inst.model = model;
    world_->instances.push_back(inst);
    return inst.id;
  }

  void Quad(const V3& a, const V3& b, const V3& c, const V3& d, Color color, uint32_t id) {
    Mesh& m = world_->mesh;
    const uint32_t base = uint32_t(m.positions.size());
    for (const V3* p : {&a, &b, &c, &d}) {
      m.positions.push_back(*p);
      m.colors.push_back(color);
    }
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base + 2, base + 3});
    world_->triangle_instance.push_back(id);
    world_->triangle_instance.push_back(id);
  }

  void FloorQuad(float x0, float y0, float x1, float y1, float z, Color c, uint32_t id) {
    Quad({x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}, c, id);
  }
  void CeilingQuad(float x0, float y0, float x1, float y1, float z, Color c, uint32_t id) {
    Quad({x0, y0, z}, {x0, y1, z}, {x1, y1, z}, {x1, y0, z}, c, id);
  }

  void Box(const V3& lo, const V3& hi, Color c, uint32_t id) {
    const float x0 = lo.x(), y0 = lo.y(), z0 = lo.z(), x1 = hi.x(), y1 = hi.y(), z1 = hi.z();
    Quad({x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0}, c, id);  // -z
    Quad({x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}, c, id);  // +z
    Quad({x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}, c, id);  // -y
    Quad({x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}, c, id);  // +y
    Quad({x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}, c, id);  // -x
    Quad({x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}, c, id);  // +x
  }

  void Cylinder(float cx, float cy, float r, float z0, float z1, Color c, uint32_t id) {
    constexpr int kSegments = 16;
    Mesh& m = world_->mesh;
    const uint32_t base = uint32_t(m.positions.size());
    for (int i = 0; i < kSegments; ++i) {
      const double a = 2.0 * kPi * i / kSegments;
      const float x = cx + float(r * std::cos(a)), y = cy + float(r * std::sin(a));
      m.positions.emplace_back(x, y, z0);
      m.positions.emplace_back(x, y, z1);
    }
    m.positions.emplace_back(cx, cy, z0);
    m.positions.emplace_back(cx, cy, z1);
    m.colors.resize(m.positions.size(), c);
    const uint32_t cb = base + 2 * kSegments, ct = cb + 1;
    for (int i = 0; i < kSegments; ++i) {
      const uint32_t b0 = base + 2 * i, t0 = b0 + 1;
      const uint32_t b1 = base + 2 * ((i + 1) % kSegments), t1 = b1 + 1;
      m.triangles.push_back({b0, b1, t1});
      m.triangles.push_back({b0, t1, t0});
      m.triangles.push_back({ct, t0, t1});
      m.triangles.push_back({cb, b1, b0});
      for (int k = 0; k < 4; ++k) world_->triangle_instance.push_back(id);
    }
  }

  // The item with its local frame turned by `quarter` and its origin at (x, y, z).
  void Emit(const Item& item, int quarter, float x, float y, float z) {
    if (!item.cls.empty()) {
      const uint32_t id = NewInstance(item.cls, item.model);
      for (const Part& p : item.parts) {
        const Eigen::Vector2f a = Rot(quarter, p.lo.x(), p.lo.y());
        const Eigen::Vector2f b = Rot(quarter, p.hi.x(), p.hi.y());
        const V3 lo(std::min(a.x(), b.x()) + x, std::min(a.y(), b.y()) + y, p.lo.z() + z);
        const V3 hi(std::max(a.x(), b.x()) + x, std::max(a.y(), b.y()) + y, p.hi.z() + z);
        if (p.cylinder) {
          const float r = 0.5f * std::min(hi.x() - lo.x(), hi.y() - lo.y());
          Cylinder(0.5f * (lo.x() + hi.x()), 0.5f * (lo.y() + hi.y()), r, lo.z(), hi.z(), p.color,
                   id);
        } else {
          Box(lo, hi, p.color, id);
        }
      }
      if (item.mesh) {
        const Mesh& src = item.mesh->mesh;
        Mesh& m = world_->mesh;
        const uint32_t base = uint32_t(m.positions.size());
        const int q = (item.mesh->quarter + quarter) & 3;
        for (size_t v = 0; v < src.positions.size(); ++v) {
          const V3& p = src.positions[v];
          const Eigen::Vector2f r = Rot(q, p.x(), p.y());
          m.positions.emplace_back(r.x() + x, r.y() + y, p.z() + z);
          m.colors.push_back(src.colors.size() == src.positions.size() ? src.colors[v]
                                                                       : Color{150, 150, 150});
        }
        for (const auto& t : src.triangles) {
          m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
          world_->triangle_instance.push_back(id);
        }
      }
    }
    for (const Item::Child& c : item.children) {
      const Eigen::Vector2f o = Rot(quarter, c.x, c.y);
      Emit(c.item, (quarter + c.quarter) & 3, x + o.x(), y + o.y(), z + c.z);
    }
  }

 private:
  World* world_;
};

// ---------------------------------------------------------------------------------------------
// Furniture catalogue.

Part BoxPart(float x0, float y0, float z0, float x1, float y1, float z1, Color c) {
  return {false, V3(x0, y0, z0), V3(x1, y1, z1), c};
}
Part CylPart(float cx, float cy, float r, float z0, float z1, Color c) {
  return {true, V3(cx - r, cy - r, z0), V3(cx + r, cy + r, z1), c};
}

// Native back direction of the AWS models (from their placements in the small house).
struct MeshSpec {
  const char* model;
  int quarter;  // native -> local (back to +y): +y 0, +x 1, -y 2, -x 3
};
constexpr MeshSpec kMeshSpecs[] = {
    {"Bed_01", 0},
    {"NightStand_01", 0},
    {"Wardrobe_01", 0},
    {"ReadingDesk_01", 3},
    {"ChairA_01", 1},
    {"ChairD_01", 3},
    {"KitchenTable_01", 1},
    {"CoffeeTable_01", 0},
    {"Refrigerator_01", 0},
    {"TVCabinet_01", 3},
    {"TV_01", 1},
    {"ShoeRack_01", 2},
    {"SofaB_01", 0},
    {"Trash_01", 0},
    {"Vase_01", 0},
    {"PortraitA_01", 0},
    {"PortraitB_01", 0},
    {"PortraitD_01", 0},
    {"PortraitE_01", 0},
    {"DeskPortraitA_01", 0},
    {"DeskPortraitB_01", 0},
    {"CookingBench_01", 1},
    {"Tableware_01", 0},
};

class Catalogue {
 public:
  Catalogue(Rng* rng, const std::vector<FurnitureModel>* index, float probability, int budget)
      : rng_(*rng), index_(index), probability_(probability), budget_(budget) {}
  const Status& status() const { return status_; }
  int mesh_triangles() const { return used_; }
  void Charge(int triangles) { used_ += triangles; }

  // A mesh for `model`, or null (no index, not drawn, over budget, or unreadable).
  const PreparedMesh* Mesh(const std::string& model, bool force = false) {
    if (!index_ || index_->empty()) return nullptr;
    const bool drawn = rng_.Chance(force ? 1.0 : probability_);
    if (!drawn) return nullptr;
    auto it = cache_.find(model);
    if (it == cache_.end()) {
      const FurnitureModel* entry = nullptr;
      for (const FurnitureModel& m : *index_)
        if (m.model == model && m.mesh_kind == "visual") entry = &m;
      int quarter = -1;
      for (const MeshSpec& s : kMeshSpecs)
        if (model == s.model) quarter = s.quarter;
      std::unique_ptr<PreparedMesh> prepared;
      if (entry && quarter >= 0) {
        MeshReadOptions options;
        options.up = UpAxis::kY;  // the DAE files read as Y-up (native Z-up)
        Result<voxplan::Mesh> mesh = ReadMesh(entry->path, options);
        if (!mesh.ok()) {
          if (status_.ok()) status_ = mesh.status().WithContext("furniture model " + model);
        } else {
          prepared = std::make_unique<PreparedMesh>();
          Eigen::AlignedBox3f box;
          for (const V3& p : mesh->positions) box.extend(p);
          const V3 shift(-box.center().x(), -box.center().y(), -box.min().z());
          for (V3& p : mesh->positions) p += shift;
          prepared->mesh.positions = std::move(mesh->positions);
          prepared->mesh.colors = std::move(mesh->colors);
          prepared->mesh.triangles = std::move(mesh->triangles);
          prepared->quarter = quarter;
          prepared->size = box.sizes();
        }
      }
      it = cache_.emplace(model, std::move(prepared)).first;
    }
    const PreparedMesh* m = it->second.get();
    if (!m || used_ + int(m->mesh.num_triangles()) > budget_) return nullptr;
    used_ += int(m->mesh.num_triangles());
    return m;
  }

  static Item MeshItem(const std::string& cls, const std::string& model, const PreparedMesh* m) {
    Item it;
    it.cls = cls;
    it.model = model;
    it.mesh = m;
    const bool swap = m->quarter & 1;
    it.w = swap ? m->size.y() : m->size.x();
    it.d = swap ? m->size.x() : m->size.y();
    it.h = m->size.z();
    return it;
  }

 private:
  Rng& rng_;
  const std::vector<FurnitureModel>* index_;
  float probability_;
  int budget_;
  int used_ = 0;
  std::map<std::string, std::unique_ptr<PreparedMesh>> cache_;
  Status status_;
};

const Color kWood{150, 105, 65}, kDarkWood{95, 65, 40}, kWhite{235, 235, 232},
    kFabric{90, 110, 140}, kMetal{160, 165, 170}, kBlack{30, 30, 32}, kCeramic{245, 245, 245};

struct Furnisher {
  Rng& rng;
  Catalogue& cat;

  Item Bed(bool dbl) {
    if (dbl)
      if (const PreparedMesh* m = cat.Mesh("Bed_01"))
        return Catalogue::MeshItem("bed", "Bed_01", m);
    Item it;
    it.cls = "bed";
    it.model = dbl ? "param_bed_double" : "param_bed_single";
    it.w = dbl ? float(rng.Uniform(1.4, 1.8)) : float(rng.Uniform(0.9, 1.0));
    it.d = float(rng.Uniform(2.0, 2.15));
    it.h = 0.95f;
    const float hw = it.w / 2, hd = it.d / 2;
    const Color frame = Jitter(kDarkWood, rng), sheet = Jitter({215, 220, 230}, rng, 20);
    it.parts.push_back(BoxPart(-hw, -hd, 0, hw, hd - 0.06f, 0.3f, frame));
    it.parts.push_back(
        BoxPart(-hw + 0.03f, -hd + 0.03f, 0.3f, hw - 0.03f, hd - 0.08f, 0.5f, sheet));
    it.parts.push_back(BoxPart(-hw, hd - 0.06f, 0, hw, hd, 0.95f, frame));  // headboard
    it.parts.push_back(BoxPart(-hw + 0.1f, hd - 0.5f, 0.5f, hw - 0.1f, hd - 0.12f, 0.62f, kWhite));
    return it;
  }
  Item Nightstand() {
    if (const PreparedMesh* m = cat.Mesh("NightStand_01"))
      return Catalogue::MeshItem("nightstand", "NightStand_01", m);
    Item it;
    it.cls = "nightstand";
    it.model = "param_nightstand";
    it.w = 0.45f;
    it.d = 0.4f;
    it.h = 0.52f;
    const Color c = Jitter(kWood, rng);
    it.parts.push_back(BoxPart(-0.225f, -0.2f, 0.05f, 0.225f, 0.2f, 0.5f, c));
    it.parts.push_back(BoxPart(-0.225f, -0.2f, 0.5f, 0.225f, 0.2f, 0.52f, Jitter(kDarkWood, rng)));
    for (float x : {-0.2f, 0.18f})
      for (float y : {-0.18f, 0.16f})
        it.parts.push_back(BoxPart(x, y, 0, x + 0.02f, y + 0.02f, 0.05f, kBlack));
    return it;
  }
  Item SmallDecor() {
    static const char* kModels[] = {"Vase_01", "DeskPortraitA_01", "DeskPortraitB_01"};
    const std::string model = kModels[rng.Int(0, 2)];
    if (const PreparedMesh* m = cat.Mesh(model)) return Catalogue::MeshItem("decor", model, m);
    Item it;
    it.cls = "decor";
    it.model = "param_vase";
    it.w = it.d = 0.12f;
    it.h = 0.25f;
    it.parts.push_back(CylPart(0, 0, 0.06f, 0, 0.25f, Jitter({60, 120, 160}, rng, 40)));
    return it;
  }
  Item Wardrobe() {
    if (const PreparedMesh* m = cat.Mesh("Wardrobe_01"))
      return Catalogue::MeshItem("wardrobe", "Wardrobe_01", m);
    Item it;
    it.cls = "wardrobe";
    it.model = "param_wardrobe";
    it.w = float(rng.Uniform(1.0, 1.8));
    it.d = 0.6f;
    it.h = float(rng.Uniform(1.9, 2.2));
    const float hw = it.w / 2;
    const Color c = Jitter(rng.Chance(0.5) ? kWhite : kWood, rng);
    it.parts.push_back(BoxPart(-hw, -0.28f, 0.08f, hw, 0.3f, it.h, c));
    it.parts.push_back(BoxPart(-hw + 0.02f, -0.26f, 0, hw - 0.02f, 0.28f, 0.08f, kDarkWood));
    for (float x : {-0.06f, 0.04f})
      it.parts.push_back(BoxPart(x, -0.3f, 0.9f, x + 0.02f, -0.28f, 1.2f, kMetal));
    return it;
  }
  Item Shelf() {
    Item it;
    it.cls = "shelf";
    it.model = "param_shelf";
    it.w = float(rng.Uniform(0.7, 1.3));
    it.d = 0.35f;
    it.h = float(rng.Uniform(1.4, 2.0));
    const float hw = it.w / 2, hd = it.d / 2;
    const Color c = Jitter(rng.Chance(0.5) ? kWood : kWhite, rng);
    it.parts.push_back(BoxPart(-hw, -hd, 0, -hw + 0.025f, hd, it.h, c));
    it.parts.push_back(BoxPart(hw - 0.025f, -hd, 0, hw, hd, it.h, c));
    it.parts.push_back(BoxPart(-hw + 0.025f, hd - 0.015f, 0, hw - 0.025f, hd, it.h, c));
    const int boards = 3 + int(it.h / 0.5f);
    for (int b = 0; b < boards; ++b) {
      const float z = 0.05f + (it.h - 0.07f) * b / (boards - 1);
      it.parts.push_back(BoxPart(-hw + 0.025f, -hd, z, hw - 0.025f, hd - 0.015f, z + 0.02f, c));
      if (b > 0 && b + 1 < boards && rng.Chance(0.6))  // books
        it.parts.push_back(BoxPart(-hw + 0.05f, -hd + 0.05f, z + 0.02f,
                                   -hw + 0.05f + float(rng.Uniform(0.15, it.w - 0.15)), hd - 0.05f,
                                   z + 0.02f + float(rng.Uniform(0.18, 0.28)),
                                   Jitter({140, 60, 50}, rng, 60)));
    }
    return it;
  }
  Item Chair() {
    static const char* kModels[] = {"ChairA_01", "ChairD_01"};
    const std::string model = kModels[rng.Int(0, 1)];
    if (const PreparedMesh* m = cat.Mesh(model)) return Catalogue::MeshItem("chair", model, m);
    Item it;
    it.cls = "chair";
    it.model = "param_chair";
    it.w = 0.44f;
    it.d = 0.46f;
    it.h = 0.9f;
    const Color c = Jitter(kWood, rng);
    it.parts.push_back(BoxPart(-0.22f, -0.23f, 0.42f, 0.22f, 0.21f, 0.46f, c));
    for (float x : {-0.22f, 0.18f})
      for (float y : {-0.23f, 0.17f})
        it.parts.push_back(BoxPart(x, y, 0, x + 0.04f, y + 0.04f, 0.42f, c));
    it.parts.push_back(BoxPart(-0.22f, 0.19f, 0.46f, 0.22f, 0.23f, 0.9f, c));
    return it;
  }
  Item Table(float w, float d, float h, bool round) {
    Item it;
    it.cls = "table";
    it.model = round ? "param_table_round" : "param_table";
    it.w = w;
    it.d = d;
    it.h = h;
    const Color c = Jitter(rng.Chance(0.5) ? kWood : kWhite, rng);
    if (round) {
      const float r = std::min(w, d) / 2;
      it.parts.push_back(CylPart(0, 0, r, h - 0.04f, h, c));
      it.parts.push_back(CylPart(0, 0, 0.04f, 0.03f, h - 0.04f, kMetal));
      it.parts.push_back(CylPart(0, 0, std::min(0.25f, r * 0.6f), 0, 0.03f, kMetal));
    } else {
      const float hw = w / 2, hd = d / 2;
      it.parts.push_back(BoxPart(-hw, -hd, h - 0.04f, hw, hd, h, c));
      for (float x : {-hw + 0.03f, hw - 0.08f})
        for (float y : {-hd + 0.03f, hd - 0.08f})
          it.parts.push_back(
              BoxPart(x, y, 0, x + 0.05f, y + 0.05f, h - 0.04f, Jitter(kDarkWood, rng)));
    }
    return it;
  }
  Item Desk() {
    if (const PreparedMesh* m = cat.Mesh("ReadingDesk_01"))
      return Catalogue::MeshItem("desk", "ReadingDesk_01", m);
    Item it = Table(float(rng.Uniform(1.1, 1.5)), float(rng.Uniform(0.6, 0.7)), 0.75f, false);
    it.cls = "desk";
    it.model = "param_desk";
    return it;
  }
  // A desk with its chair in front (the chair faces the desk).
  Item DeskGroup() {
    Item desk = Desk(), chair = Chair();
    Item g;
    g.w = std::max(desk.w, chair.w);
    g.d = desk.d + 0.1f + chair.d;
    g.children.push_back({desk, 0, g.d / 2 - desk.d / 2, 0, 0});
    g.children.push_back({chair, 0, -g.d / 2 + chair.d / 2, 0, 2});
    return g;
  }
  Item DiningGroup(int chairs_per_side) {
    Item table;
    if (const PreparedMesh* m = cat.Mesh("KitchenTable_01")) {
      table = Catalogue::MeshItem("table", "KitchenTable_01", m);
    } else {
      const bool round = chairs_per_side == 1 && rng.Chance(0.4);
      const float w =
          round ? 0.9f
                : float(chairs_per_side == 1 ? rng.Uniform(0.8, 1.0) : rng.Uniform(1.4, 1.8));
      table = Table(w, round ? 0.9f : float(rng.Uniform(0.8, 0.9)), 0.75f, round);
    }
    Item g;
    const Item proto = Chair();
    g.w = std::max(table.w, chairs_per_side * (proto.w + 0.15f));
    g.d = table.d + 2 * (proto.d + 0.05f);
    g.children.push_back({table, 0, 0, 0, 0});
    for (int side = 0; side < 2; ++side)
      for (int k = 0; k < chairs_per_side; ++k) {
        const Item& chair = proto;  // one model around a table
        if (side + k > 0 && proto.mesh) cat.Charge(int(proto.mesh->mesh.num_triangles()));
        const float x = chairs_per_side == 1 ? 0.0f : (k == 0 ? -1 : 1) * g.w / 4;
        const float y = (side == 0 ? -1 : 1) * (g.d / 2 - chair.d / 2);
        // Chairs face the table: the south one's back at -y.
        g.children.push_back({chair, x, y, 0, side == 0 ? 2 : 0});
      }
    return g;
  }
  Item Sofa() {
    Item it;
    it.cls = "sofa";
    it.model = "param_sofa";
    it.w = float(rng.Uniform(1.8, 2.4));
    it.d = 0.9f;
    it.h = 0.85f;
    const float hw = it.w / 2;
    const Color c = Jitter(kFabric, rng, 40);
    it.parts.push_back(BoxPart(-hw, -0.45f, 0.08f, hw, 0.45f, 0.42f, c));
    it.parts.push_back(BoxPart(-hw, 0.25f, 0.42f, hw, 0.45f, 0.85f, c));
    it.parts.push_back(BoxPart(-hw, -0.45f, 0.42f, -hw + 0.15f, 0.25f, 0.62f, c));
    it.parts.push_back(BoxPart(hw - 0.15f, -0.45f, 0.42f, hw, 0.25f, 0.62f, c));
    for (float x : {-hw + 0.05f, hw - 0.09f})
      for (float y : {-0.4f, 0.36f})
        it.parts.push_back(BoxPart(x, y, 0, x + 0.04f, y + 0.04f, 0.08f, kBlack));
    return it;
  }
  Item Armchair() {
    if (const PreparedMesh* m = cat.Mesh("SofaB_01"))
      return Catalogue::MeshItem("sofa", "SofaB_01", m);
    Item it;
    it.cls = "sofa";
    it.model = "param_armchair";
    it.w = 0.85f;
    it.d = 0.85f;
    it.h = 0.85f;
    const Color c = Jitter(kFabric, rng, 50);
    it.parts.push_back(BoxPart(-0.425f, -0.425f, 0, 0.425f, 0.425f, 0.42f, c));
    it.parts.push_back(BoxPart(-0.425f, 0.225f, 0.42f, 0.425f, 0.425f, 0.85f, c));
    it.parts.push_back(BoxPart(-0.425f, -0.425f, 0.42f, -0.3f, 0.225f, 0.62f, c));
    it.parts.push_back(BoxPart(0.3f, -0.425f, 0.42f, 0.425f, 0.225f, 0.62f, c));
    return it;
  }
  Item CoffeeTable() {
    if (const PreparedMesh* m = cat.Mesh("CoffeeTable_01")) {
      Item it = Catalogue::MeshItem("table", "CoffeeTable_01", m);
      return it;
    }
    Item it = Table(float(rng.Uniform(0.9, 1.2)), 0.55f, 0.42f, false);
    it.model = "param_coffee_table";
    return it;
  }
  // Sofa with a coffee table in front of it.
  Item SofaGroup() {
    Item sofa = Sofa(), table = CoffeeTable();
    if (table.w > sofa.w) return sofa;
    Item g;
    g.w = sofa.w;
    g.d = sofa.d + 0.4f + table.d;
    g.children.push_back({sofa, 0, g.d / 2 - sofa.d / 2, 0, 0});
    g.children.push_back({table, 0, -g.d / 2 + table.d / 2, 0, 0});
    return g;
  }
  Item TvGroup() {
    Item stand;
    if (const PreparedMesh* m = cat.Mesh("TVCabinet_01")) {
      stand = Catalogue::MeshItem("cabinet", "TVCabinet_01", m);
    } else {
      stand.cls = "cabinet";
      stand.model = "param_tv_stand";
      stand.w = float(rng.Uniform(1.4, 1.8));
      stand.d = 0.42f;
      stand.h = 0.5f;
      stand.parts.push_back(
          BoxPart(-stand.w / 2, -0.21f, 0.05f, stand.w / 2, 0.21f, 0.5f, Jitter(kWhite, rng)));
      stand.parts.push_back(
          BoxPart(-stand.w / 2 + 0.05f, -0.19f, 0, stand.w / 2 - 0.05f, 0.19f, 0.05f, kBlack));
    }
    Item tv;
    if (const PreparedMesh* m = cat.Mesh("TV_01")) {
      tv = Catalogue::MeshItem("tv", "TV_01", m);
    } else {
      tv.cls = "tv";
      tv.model = "param_tv";
      tv.w = 1.1f;
      tv.d = 0.2f;
      tv.h = 0.7f;
      tv.parts.push_back(BoxPart(-0.55f, 0.02f, 0.06f, 0.55f, 0.08f, 0.7f, kBlack));
      tv.parts.push_back(BoxPart(-0.15f, -0.1f, 0, 0.15f, 0.1f, 0.02f, kBlack));
      tv.parts.push_back(BoxPart(-0.03f, 0.0f, 0.02f, 0.03f, 0.04f, 0.1f, kBlack));
    }
    if (tv.w > stand.w || tv.d > stand.d) return stand;
    stand.children.push_back({tv, 0, stand.d / 2 - tv.d / 2 - 0.02f, stand.h, 0});
    return stand;
  }
  Item Counter(float length) {
    Item it;
    it.cls = "cabinet";
    it.model = "param_kitchen_counter";
    it.w = length;
    it.d = 0.62f;
    it.h = 2.1f;
    const float hw = length / 2;
    const Color body = Jitter(rng.Chance(0.5) ? kWhite : Color{120, 140, 120}, rng);
    it.parts.push_back(BoxPart(-hw, -0.28f, 0.1f, hw, 0.31f, 0.87f, body));
    it.parts.push_back(BoxPart(-hw + 0.02f, -0.25f, 0, hw - 0.02f, 0.31f, 0.1f, kBlack));
    it.parts.push_back(BoxPart(-hw, -0.31f, 0.87f, hw, 0.31f, 0.9f, Jitter({70, 70, 75}, rng)));
    it.parts.push_back(BoxPart(-hw, -0.04f, 1.45f, hw, 0.31f, 2.1f, body));  // wall cabinets
    if (const PreparedMesh* m = cat.Mesh("CookingBench_01")) {
      Item stove = Catalogue::MeshItem("appliance", "CookingBench_01", m);
      if (stove.w < length - 0.1f && stove.d < it.d)
        it.children.push_back({stove, -hw + stove.w / 2 + 0.05f, 0, 0.9f, 0});
    } else {
      Item stove;
      stove.cls = "appliance";
      stove.model = "param_cooktop";
      stove.w = 0.6f;
      stove.d = 0.5f;
      stove.h = 0.02f;
      stove.parts.push_back(BoxPart(-0.3f, -0.25f, 0, 0.3f, 0.25f, 0.02f, kBlack));
      if (length > 0.8f) it.children.push_back({stove, -hw + 0.4f, -0.02f, 0.9f, 0});
    }
    return it;
  }
  Item Fridge() {
    if (const PreparedMesh* m = cat.Mesh("Refrigerator_01"))
      return Catalogue::MeshItem("appliance", "Refrigerator_01", m);
    Item it;
    it.cls = "appliance";
    it.model = "param_fridge";
    it.w = 0.6f;
    it.d = 0.65f;
    it.h = 1.85f;
    it.parts.push_back(BoxPart(-0.3f, -0.3f, 0.02f, 0.3f, 0.325f, 1.85f, Jitter(kMetal, rng)));
    it.parts.push_back(BoxPart(0.2f, -0.325f, 0.9f, 0.23f, -0.3f, 1.5f, kBlack));
    return it;
  }
  Item Bin() {
    if (const PreparedMesh* m = cat.Mesh("Trash_01"))
      return Catalogue::MeshItem("bin", "Trash_01", m);
    Item it;
    it.cls = "bin";
    it.model = "param_bin";
    it.w = it.d = 0.3f;
    it.h = 0.4f;
    it.parts.push_back(CylPart(0, 0, 0.15f, 0, 0.4f, Jitter(kMetal, rng, 30)));
    return it;
  }
  Item Plant() {
    Item it;
    it.cls = "plant";
    it.model = "param_plant";
    const float r = float(rng.Uniform(0.2, 0.3));
    it.w = it.d = 2 * r;
    it.h = float(rng.Uniform(0.8, 1.5));
    it.parts.push_back(CylPart(0, 0, 0.14f, 0, 0.3f, Jitter({170, 90, 60}, rng)));
    it.parts.push_back(CylPart(0, 0, r, 0.3f, it.h, Jitter({60, 120, 50}, rng, 25)));
    return it;
  }
  Item Bathtub() {
    Item it;
    it.cls = "bathtub";
    it.model = "param_bathtub";
    it.w = float(rng.Uniform(1.5, 1.75));
    it.d = 0.75f;
    it.h = 0.55f;
    const float hw = it.w / 2;
    it.parts.push_back(BoxPart(-hw, -0.375f, 0, hw, 0.375f, 0.1f, kCeramic));
    it.parts.push_back(BoxPart(-hw, -0.375f, 0.1f, hw, -0.305f, 0.55f, kCeramic));
    it.parts.push_back(BoxPart(-hw, 0.305f, 0.1f, hw, 0.375f, 0.55f, kCeramic));
    it.parts.push_back(BoxPart(-hw, -0.305f, 0.1f, -hw + 0.07f, 0.305f, 0.55f, kCeramic));
    it.parts.push_back(BoxPart(hw - 0.07f, -0.305f, 0.1f, hw, 0.305f, 0.55f, kCeramic));
    return it;
  }
  Item Toilet() {
    Item it;
    it.cls = "toilet";
    it.model = "param_toilet";
    it.w = 0.4f;
    it.d = 0.68f;
    it.h = 0.8f;
    it.parts.push_back(BoxPart(-0.2f, 0.16f, 0.35f, 0.2f, 0.34f, 0.8f, kCeramic));
    it.parts.push_back(CylPart(0, -0.06f, 0.19f, 0, 0.42f, kCeramic));
    it.parts.push_back(BoxPart(-0.12f, -0.06f, 0, 0.12f, 0.16f, 0.4f, kCeramic));
    return it;
  }
  Item Sink() {
    Item it;
    it.cls = "sink";
    it.model = "param_sink";
    it.w = float(rng.Uniform(0.5, 0.8));
    it.d = 0.46f;
    it.h = 0.88f;
    const float hw = it.w / 2;
    it.parts.push_back(BoxPart(-hw, -0.23f, 0, hw, 0.23f, 0.8f, Jitter(kWhite, rng)));
    it.parts.push_back(BoxPart(-hw, -0.23f, 0.8f, hw, 0.23f, 0.88f, kCeramic));
    return it;
  }
  Item ShoeRack() {
    if (const PreparedMesh* m = cat.Mesh("ShoeRack_01"))
      return Catalogue::MeshItem("cabinet", "ShoeRack_01", m);
    Item it;
    it.cls = "cabinet";
    it.model = "param_console";
    it.w = float(rng.Uniform(0.8, 1.1));
    it.d = 0.32f;
    it.h = 0.9f;
    it.parts.push_back(BoxPart(-it.w / 2, -0.16f, 0, it.w / 2, 0.16f, 0.9f, Jitter(kWood, rng)));
    return it;
  }
  Item SideCabinet() {
    Item it;
    it.cls = "cabinet";
    it.model = "param_sideboard";
    it.w = float(rng.Uniform(1.2, 1.8));
    it.d = 0.45f;
    it.h = 0.85f;
    it.parts.push_back(
        BoxPart(-it.w / 2, -0.225f, 0.1f, it.w / 2, 0.225f, 0.85f, Jitter(kWood, rng)));
    it.parts.push_back(BoxPart(-it.w / 2 + 0.03f, -0.2f, 0, it.w / 2 - 0.03f, 0.2f, 0.1f, kBlack));
    return it;
  }
  // A picture on the wall, 1.2-1.5 m up; a group so the footprint is the picture's.
  Item Portrait() {
    static const char* kModels[] = {"PortraitA_01", "PortraitB_01", "PortraitD_01", "PortraitE_01"};
    const std::string model = kModels[rng.Int(0, 3)];
    Item pic;
    if (const PreparedMesh* m = cat.Mesh(model)) {
      pic = Catalogue::MeshItem("decor", model, m);
    } else {
      pic.cls = "decor";
      pic.model = "param_picture";
      pic.w = float(rng.Uniform(0.4, 0.9));
      pic.d = 0.03f;
      pic.h = float(rng.Uniform(0.3, 0.6));
      pic.parts.push_back(BoxPart(-pic.w / 2, -0.015f, 0, pic.w / 2, 0.015f, pic.h,
                                  Jitter({120, 100, 140}, rng, 60)));
    }
    Item g;
    g.w = pic.w;
    g.d = pic.d;
    g.children.push_back({pic, 0, 0, float(rng.Uniform(1.2, 1.5)), 0});
    return g;
  }
  Item Rug(float max_w, float max_d) {
    Item it;
    it.cls = "carpet";
    it.model = "param_rug";
    it.w = std::min(max_w, float(rng.Uniform(1.4, 2.4)));
    it.d = std::min(max_d, float(rng.Uniform(1.0, 1.8)));
    it.h = 0.012f;
    it.walkable = true;
    it.parts.push_back(BoxPart(-it.w / 2, -it.d / 2, 0.002f, it.w / 2, it.d / 2, 0.012f,
                               Jitter({150, 60, 60}, rng, 60)));
    return it;
  }
};

// ---------------------------------------------------------------------------------------------
// Placement within one room: a 5 cm grid over the room interior plus a border; walls (the
// border) and furniture footprints are blocked; door zones are reserved (no furniture). The
// robot-centre space is the unblocked space eroded by the robot radius; every placement must keep
// it one connected piece that reaches every door, for each of the radii below (a pocket closed to
// a 0.25 m robot can be open, and cut off, for a 0.2 m one).

constexpr float kRobotRadii[2] = {0.2f, 0.25f};
constexpr float kRobotRadius = 0.25f;  // the largest
constexpr float kWallGap = 0.02f;
constexpr float kDoorZoneDepth = 1.0f;

struct DoorSide {
  int side;      // 0 north (+y), 1 west (-x), 2 south (-y), 3 east (+x)
  float o0, o1;  // opening along the wall, metres
};

struct Placement {
  float x, y;
  int quarter;
};

class RoomPlanner {
 public:
  RoomPlanner(const RectU& r, const std::vector<DoorSide>& doors)
      : x0_(M(r.x0)), y0_(M(r.y0)), x1_(M(r.x1)), y1_(M(r.y1)), doors_(doors) {
    pad_ = int(std::ceil(kRobotRadius / kUnit)) + 2;
    gw_ = (r.x1 - r.x0) + 2 * pad_;
    gh_ = (r.y1 - r.y0) + 2 * pad_;
    ox_ = x0_ - float(pad_ * kUnit);
    oy_ = y0_ - float(pad_ * kUnit);
    blocked_.assign(size_t(gw_) * gh_, 0);
    reserved_.assign(blocked_.size(), 0);
    for (int k = 0; k < 2; ++k) {
      inflated_[k].assign(blocked_.size(), 0);
      const int rc = int(std::ceil(kRobotRadii[k] / kUnit));
      for (int dj = -rc; dj <= rc; ++dj)
        for (int di = -rc; di <= rc; ++di) {
          const double dx = std::max(0.0, std::abs(di) - 0.5);
          const double dy = std::max(0.0, std::abs(dj) - 0.5);
          if (std::hypot(dx, dy) * kUnit < kRobotRadii[k]) offsets_[k].push_back({di, dj});
        }
    }
    for (int j = 0; j < gh_; ++j)
      for (int i = 0; i < gw_; ++i)
        if (!Interior(i, j)) blocked_[Index(i, j)] = 1;
    for (const DoorSide& d : doors_) {
      // The opening and what lies beyond it is not a wall.
      const bool along_x = d.side == 0 || d.side == 2;
      for (int j = 0; j < gh_; ++j)
        for (int i = 0; i < gw_; ++i) {
          if (Interior(i, j)) continue;
          const float cx = ox_ + float((i + 0.5) * kUnit), cy = oy_ + float((j + 0.5) * kUnit);
          const float along = along_x ? cx : cy;
          const bool beyond = d.side == 0   ? cy > y1_
                              : d.side == 2 ? cy < y0_
                              : d.side == 1 ? cx < x0_
                                            : cx > x1_;
          const bool within_other = along_x ? (cx > x0_ && cx < x1_) : (cy > y0_ && cy < y1_);
          if (beyond && within_other && along > d.o0 && along < d.o1) blocked_[Index(i, j)] = 0;
        }
      MarkRect(ZoneRect(d), &reserved_);
    }
    for (int j = 0; j < gh_; ++j)
      for (int i = 0; i < gw_; ++i)
        if (blocked_[Index(i, j)])
          for (int k = 0; k < 2; ++k) Inflate(i, j, k, &inflated_[k]);
  }

  float x0() const { return x0_; }
  float y0() const { return y0_; }
  float x1() const { return x1_; }
  float y1() const { return y1_; }

  // Tries wall-backed placements (sides in random order, positions along each side).
  bool PlaceAgainstWall(const Item& item, Rng& rng, Placement* out, int tries_per_side = 6) {
    std::vector<int> sides = {0, 1, 2, 3};
    rng.Shuffle(&sides);
    for (int side : sides) {
      const int q = side;  // local +y (the back) turned towards the wall
      const float ex = (q & 1) ? item.d : item.w, ey = (q & 1) ? item.w : item.d;
      const bool along_x = side == 0 || side == 2;
      const float lo = (along_x ? x0_ : y0_) + kWallGap + (along_x ? ex : ey) / 2;
      const float hi = (along_x ? x1_ : y1_) - kWallGap - (along_x ? ex : ey) / 2;
      if (hi < lo) continue;
      for (int t = 0; t < tries_per_side; ++t) {
        const float a = t == 0 ? lo : t == 1 ? hi : float(rng.Uniform(lo, hi));
        Placement p{0.0f, 0.0f, 0};
        p.quarter = q;
        if (side == 0) p = {a, y1_ - kWallGap - ey / 2, q};
        if (side == 2) p = {a, y0_ + kWallGap + ey / 2, q};
        if (side == 1) p = {x0_ + kWallGap + ex / 2, a, q};
        if (side == 3) p = {x1_ - kWallGap - ex / 2, a, q};
        if (TryCommit(item, p)) {
          *out = p;
          return true;
        }
      }
    }
    return false;
  }

  // Tries free-standing placements anywhere in the room.
  bool PlaceFree(const Item& item, Rng& rng, Placement* out, int tries = 24) {
    for (int t = 0; t < tries; ++t) {
      const int q = rng.Int(0, 3);
      const float ex = (q & 1) ? item.d : item.w, ey = (q & 1) ? item.w : item.d;
      const float lx = x0_ + kWallGap + ex / 2, hx = x1_ - kWallGap - ex / 2;
      const float ly = y0_ + kWallGap + ey / 2, hy = y1_ - kWallGap - ey / 2;
      if (hx < lx || hy < ly) return false;
      Placement p{float(rng.Uniform(lx, hx)), float(rng.Uniform(ly, hy)), q};
      if (TryCommit(item, p)) {
        *out = p;
        return true;
      }
    }
    return false;
  }

 private:
  struct RectM {
    float x0, y0, x1, y1;
  };
  size_t Index(int i, int j) const { return size_t(j) * gw_ + i; }
  bool Interior(int i, int j) const {
    return i >= pad_ && j >= pad_ && i < gw_ - pad_ && j < gh_ - pad_;
  }
  RectM ZoneRect(const DoorSide& d) const {
    const float a0 = d.o0 - 0.1f, a1 = d.o1 + 0.1f;
    switch (d.side) {
      case 0:
        return {a0, y1_ - kDoorZoneDepth, a1, y1_};
      case 2:
        return {a0, y0_, a1, y0_ + kDoorZoneDepth};
      case 1:
        return {x0_, a0, x0_ + kDoorZoneDepth, a1};
      default:
        return {x1_ - kDoorZoneDepth, a0, x1_, a1};
    }
  }
  // Cells the rectangle overlaps (touching a border is not overlapping).
  void CellRange(const RectM& r, int* i0, int* j0, int* i1, int* j1) const {
    constexpr double eps = 1e-4;
    *i0 = std::max(0, int(std::floor((r.x0 - ox_) / kUnit + eps)));
    *j0 = std::max(0, int(std::floor((r.y0 - oy_) / kUnit + eps)));
    *i1 = std::min(gw_ - 1, int(std::ceil((r.x1 - ox_) / kUnit - eps)) - 1);
    *j1 = std::min(gh_ - 1, int(std::ceil((r.y1 - oy_) / kUnit - eps)) - 1);
  }
  void MarkRect(const RectM& r, std::vector<uint8_t>* grid) const {
    int i0, j0, i1, j1;
    CellRange(r, &i0, &j0, &i1, &j1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) (*grid)[Index(i, j)] = 1;
  }
  void Inflate(int i, int j, int k, std::vector<uint8_t>* grid) const {
    for (const auto& o : offsets_[k]) {
      const int a = i + o[0], b = j + o[1];
      if (a >= 0 && b >= 0 && a < gw_ && b < gh_) (*grid)[Index(a, b)] = 1;
    }
  }
  // The world footprints of what the item puts on the floor: its own rectangle (which covers
  // what stands on it), or for a group each member's, so that a group's bounding rectangle does
  // not hide free pockets between its members. Walkable ones (rugs) are flagged.
  struct Footprint {
    RectM r;
    bool walkable;
  };
  void Footprints(const Item& item, int q, float x, float y, std::vector<Footprint>* out) const {
    if (!item.cls.empty() || item.children.empty()) {
      const Eigen::Vector2f a = Rot(q, -item.w / 2, -item.d / 2),
                            b = Rot(q, item.w / 2, item.d / 2);
      out->push_back({{x + std::min(a.x(), b.x()), y + std::min(a.y(), b.y()),
                       x + std::max(a.x(), b.x()), y + std::max(a.y(), b.y())},
                      item.walkable});
      return;
    }
    for (const Item::Child& c : item.children) {
      const Eigen::Vector2f o = Rot(q, c.x, c.y);
      Footprints(c.item, (q + c.quarter) & 3, x + o.x(), y + o.y(), out);
    }
  }

  bool TryCommit(const Item& item, const Placement& p) {
    std::vector<Footprint> prints;
    Footprints(item, p.quarter, p.x, p.y, &prints);
    std::vector<RectM> rects;
    for (const Footprint& f : prints) {
      const RectM& r = f.r;
      if (r.x0 < x0_ + kWallGap - 1e-4f || r.y0 < y0_ + kWallGap - 1e-4f ||
          r.x1 > x1_ - kWallGap + 1e-4f || r.y1 > y1_ - kWallGap + 1e-4f)
        return false;
      if (f.walkable) continue;
      int i0, j0, i1, j1;
      CellRange(r, &i0, &j0, &i1, &j1);
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i)
          if (blocked_[Index(i, j)] || reserved_[Index(i, j)]) return false;
      rects.push_back(r);
    }
    if (rects.empty()) return true;
    std::array<std::vector<uint8_t>, 2> inflated;
    std::vector<std::array<int, 2>> cells;
    for (int k = 0; k < 2; ++k) {
      inflated[k] = inflated_[k];
      for (const RectM& r : rects) {
        int i0, j0, i1, j1;
        CellRange(r, &i0, &j0, &i1, &j1);
        for (int j = j0; j <= j1; ++j)
          for (int i = i0; i <= i1; ++i) {
            if (k == 0) cells.push_back({i, j});
            // Inflating the footprint's border cells is enough: inner cells' discs lie inside.
            if (i == i0 || i == i1 || j == j0 || j == j1)
              Inflate(i, j, k, &inflated[k]);
            else
              inflated[k][Index(i, j)] = 1;
          }
      }
      if (!Navigable(inflated[k])) return false;
    }
    for (const auto& c : cells) blocked_[Index(c[0], c[1])] = 1;
    inflated_ = std::move(inflated);
    return true;
  }

  // The free robot-centre cells of the interior form one piece that reaches every door.
  bool Navigable(const std::vector<uint8_t>& inflated) const {
    std::vector<uint8_t> seen(inflated.size(), 0);
    std::vector<size_t> stack;
    size_t total = 0;
    for (int j = pad_; j < gh_ - pad_; ++j)
      for (int i = pad_; i < gw_ - pad_; ++i) total += !inflated[Index(i, j)];
    std::vector<size_t> targets;
    for (const DoorSide& d : doors_) {
      const float mid = 0.5f * (d.o0 + d.o1), depth = kRobotRadius + 0.1f;
      float x = 0, y = 0;
      if (d.side == 0) x = mid, y = y1_ - depth;
      if (d.side == 2) x = mid, y = y0_ + depth;
      if (d.side == 1) x = x0_ + depth, y = mid;
      if (d.side == 3) x = x1_ - depth, y = mid;
      const int i = int(std::floor((x - ox_) / kUnit)), j = int(std::floor((y - oy_) / kUnit));
      if (i < 0 || j < 0 || i >= gw_ || j >= gh_) continue;
      if (inflated[Index(i, j)]) return false;
      targets.push_back(Index(i, j));
    }
    size_t start = SIZE_MAX;
    if (!targets.empty()) {
      start = targets[0];
    } else {
      for (int j = pad_; j < gh_ - pad_ && start == SIZE_MAX; ++j)
        for (int i = pad_; i < gw_ - pad_ && start == SIZE_MAX; ++i)
          if (!inflated[Index(i, j)]) start = Index(i, j);
    }
    if (start == SIZE_MAX) return total == 0;
    size_t reached = 0;
    stack.push_back(start);
    seen[start] = 1;
    while (!stack.empty()) {
      const size_t c = stack.back();
      stack.pop_back();
      ++reached;
      const int i = int(c % gw_), j = int(c / gw_);
      const int ni[4] = {i + 1, i - 1, i, i}, nj[4] = {j, j, j + 1, j - 1};
      for (int k = 0; k < 4; ++k) {
        if (!Interior(ni[k], nj[k])) continue;
        const size_t n = Index(ni[k], nj[k]);
        if (seen[n] || inflated[n]) continue;
        seen[n] = 1;
        stack.push_back(n);
      }
    }
    for (size_t t : targets)
      if (!seen[t]) return false;
    return reached == total;
  }

  float x0_, y0_, x1_, y1_;
  std::vector<DoorSide> doors_;
  int pad_, gw_, gh_;
  float ox_, oy_;
  std::vector<uint8_t> blocked_, reserved_;
  std::array<std::vector<uint8_t>, 2> inflated_;
  std::array<std::vector<std::array<int, 2>>, 2> offsets_;
};

void FurnishRoom(const RoomU& room, const std::vector<DoorSide>& doors, Furnisher& f, Rng& rng,
                 Emitter& emit) {
  RoomPlanner planner(room.r, doors);
  const float area = (planner.x1() - planner.x0()) * (planner.y1() - planner.y0());
  auto wall = [&](const Item& item) {
    Placement p{0.0f, 0.0f, 0};
    if (planner.PlaceAgainstWall(item, rng, &p)) {
      emit.Emit(item, p.quarter, p.x, p.y, 0.0f);
      return true;
    }
    return false;
  };
  auto free = [&](const Item& item) {
    Placement p{0.0f, 0.0f, 0};
    if (planner.PlaceFree(item, rng, &p)) {
      emit.Emit(item, p.quarter, p.x, p.y, 0.0f);
      return true;
    }
    return false;
  };
  auto maybe = [&](double p) { return rng.Chance(p); };
  const std::string& t = room.type;
  if (t == "bedroom") {
    const bool dbl = area >= 10.5f && maybe(0.8);
    Item bed = f.Bed(dbl);
    Item group;
    const int stands = dbl ? 2 : 1;
    group.w = bed.w;
    group.d = bed.d;
    std::vector<Item> ns;
    for (int k = 0; k < stands; ++k) ns.push_back(f.Nightstand());
    for (const Item& n : ns) group.w += n.w + 0.05f;
    group.d = std::max(bed.d, ns[0].d);
    float x = -group.w / 2;
    if (stands == 2) {
      group.children.push_back({ns[0], x + ns[0].w / 2, group.d / 2 - ns[0].d / 2, 0, 0});
      if (maybe(0.6))
        group.children.back().item.children.push_back({f.SmallDecor(), 0, 0, ns[0].h, 0});
      x += ns[0].w + 0.05f;
    }
    group.children.push_back({bed, x + bed.w / 2, group.d / 2 - bed.d / 2, 0, 0});
    x += bed.w + 0.05f;
    const Item& last = ns.back();
    group.children.push_back({last, x + last.w / 2, group.d / 2 - last.d / 2, 0, 0});
    if (!wall(group)) wall(bed);
    wall(f.Wardrobe());
    if (area > 9.0f && maybe(0.6)) wall(f.DeskGroup());
    if (maybe(0.5)) wall(f.Shelf());
    if (maybe(0.5)) wall(f.Plant());
    if (maybe(0.6)) wall(f.Portrait());
    if (area > 16.0f) {  // large bedrooms get a reading corner
      if (maybe(0.7)) wall(f.Armchair());
      if (maybe(0.6)) wall(f.Shelf());
      if (maybe(0.6)) wall(f.SideCabinet());
    }
    if (maybe(0.3)) free(f.Rug(1.6f, 1.2f));
  } else if (t == "living") {
    wall(f.SofaGroup());
    wall(f.TvGroup());
    if (maybe(0.7)) wall(f.Armchair());
    wall(f.Shelf());
    if (maybe(0.5)) wall(f.Shelf());
    if (area > 22.0f && maybe(0.7)) free(f.DiningGroup(2));
    for (int k = 0; k < 2; ++k)
      if (maybe(0.6)) wall(f.Plant());
    for (int k = 0; k < 2; ++k)
      if (maybe(0.6)) wall(f.Portrait());
    if (area > 35.0f) {
      wall(f.Armchair());
      wall(f.SideCabinet());
      if (maybe(0.6)) wall(f.Shelf());
      if (maybe(0.6)) wall(f.Plant());
    }
    if (maybe(0.5)) free(f.Rug(2.4f, 1.8f));
  } else if (t == "dining") {
    if (!free(f.DiningGroup(2))) free(f.DiningGroup(1));
    wall(f.SideCabinet());
    if (maybe(0.6)) wall(f.Shelf());
    if (maybe(0.6)) wall(f.Plant());
    if (maybe(0.6)) wall(f.Portrait());
    if (area > 30.0f) {
      wall(f.Shelf());
      if (maybe(0.6)) wall(f.Armchair());
    }
  } else if (t == "kitchen") {
    const float longest = std::max(planner.x1() - planner.x0(), planner.y1() - planner.y0());
    const float len = std::min(longest - 0.3f, float(rng.Uniform(1.8, 3.2)));
    if (len > 1.0f && !wall(f.Counter(len))) wall(f.Counter(std::max(1.0f, len * 0.6f)));
    wall(f.Fridge());
    if (area > 8.0f && !free(f.DiningGroup(area > 13.0f ? 2 : 1))) free(f.DiningGroup(1));
    if (maybe(0.7)) wall(f.Bin());
    if (maybe(0.4)) wall(f.Plant());
    if (area > 18.0f) wall(f.SideCabinet());
  } else if (t == "bathroom") {
    if (!wall(f.Bathtub())) wall(f.Sink());
    wall(f.Toilet());
    wall(f.Sink());
    if (maybe(0.4)) wall(f.Shelf());
    if (maybe(0.5)) wall(f.Bin());
  } else if (t == "wc") {
    wall(f.Toilet());
    wall(f.Sink());
    if (area > 6.0f && maybe(0.6)) wall(f.Shelf());
  } else if (t == "study") {
    wall(f.DeskGroup());
    wall(f.Shelf());
    if (maybe(0.6)) wall(f.Shelf());
    if (maybe(0.6)) wall(f.Armchair());
    if (maybe(0.5)) wall(f.Plant());
    if (maybe(0.5)) wall(f.Portrait());
    if (area > 16.0f) {
      wall(f.SideCabinet());
      if (maybe(0.6)) wall(f.Shelf());
    }
  } else if (t == "storage") {
    const int shelves = 2 + int(area / 5.0f);
    for (int k = 0; k < shelves; ++k) wall(f.Shelf());
  } else if (t == "corridor") {
    wall(f.ShoeRack());
    if (maybe(0.5)) wall(f.Portrait());
    if (maybe(0.3)) wall(f.Plant());
  }
}

// The wall boxes of one wall line: segments between openings (full height) and lintels.
void EmitWall(const WallU& w, const std::vector<DoorU>& doors, int H, Emitter& emit, Rng& rng) {
  std::vector<const DoorU*> openings;
  for (int d : w.doors) openings.push_back(&doors[d]);
  std::sort(openings.begin(), openings.end(),
            [](const DoorU* a, const DoorU* b) { return a->o0 < b->o0; });
  const Color wall_color = Jitter({232, 228, 218}, rng, 6);
  auto box = [&](int a0, int a1, int z0, int z1, const char* model) {
    if (a1 <= a0 || z1 <= z0) return;
    const uint32_t id = emit.NewInstance("wall", model);
    if (w.along_x)
      emit.Box({M(a0), M(w.t0), M(z0)}, {M(a1), M(w.t1), M(z1)}, wall_color, id);
    else
      emit.Box({M(w.t0), M(a0), M(z0)}, {M(w.t1), M(a1), M(z1)}, wall_color, id);
  };
  int a = w.a0;
  for (const DoorU* d : openings) {
    box(a, d->o0, 0, H, "wall_segment");
    box(d->o0, d->o1, d->height, H, "lintel");
    if (d->closed) {
      // The entrance door: a 5 cm slab in the middle of the wall filling the opening.
      const int mid = (w.t0 + w.t1) / 2;
      const uint32_t id = emit.NewInstance("door", "param_door_slab");
      const Color c = Jitter(kDarkWood, rng);
      // 1 cm below the lintel: a slab top flush with the lintel's underside would hide the
      // slab from RasterizeFloorPlan's inside-a-solid test.
      const float top = M(d->height) - 0.01f;
      if (w.along_x)
        emit.Box({M(d->o0), M(mid - 1), 0}, {M(d->o1), M(mid), top}, c, id);
      else
        emit.Box({M(mid - 1), M(d->o0), 0}, {M(mid), M(d->o1), top}, c, id);
    }
    a = d->o1;
  }
  box(a, w.a1, 0, H, "wall_segment");
}

}  // namespace

void ApartmentAreaRange(ApartmentSize size, float* min_m2, float* max_m2) {
  switch (size) {
    case ApartmentSize::kS:
      *min_m2 = 60.0f, *max_m2 = 110.0f;
      break;
    case ApartmentSize::kM:
      *min_m2 = 110.0f, *max_m2 = 200.0f;
      break;
    default:
      *min_m2 = 200.0f, *max_m2 = 350.0f;
      break;
  }
}

Result<World> GenerateApartment(const ApartmentParams& params) {
  if (!(params.mesh_probability >= 0.0f && params.mesh_probability <= 1.0f))
    return InvalidArgument("mesh_probability must be in [0, 1]");
  std::vector<FurnitureModel> index;
  if (params.furniture && !params.furniture_index.empty()) {
    Result<std::vector<FurnitureModel>> read = ReadFurnitureIndex(params.furniture_index);
    if (!read.ok()) return read.status();
    index = std::move(read.value());
  }
  Rng rng(params.seed);
  const Layout L = MakeLayout(params.size, rng);

  World world;
  world.name = std::string("apartment_") + ApartmentSizeName(params.size) + "_seed" +
               std::to_string(params.seed);
  Emitter emit(&world);
  for (const WallU& w : L.walls) EmitWall(w, L.doors, L.H, emit, rng);

  // Floors (room interior + the thresholds it owns) and ceilings, one instance each per room.
  const float H = M(L.H);
  for (size_t r = 0; r < L.rooms.size(); ++r) {
    const RoomU& room = L.rooms[r];
    const Color floor_color = room.type == "bathroom" || room.type == "wc" || room.type == "kitchen"
                                  ? Jitter({200, 200, 195}, rng, 10)
                                  : Jitter({165, 125, 85}, rng, 15);
    const uint32_t fid = emit.NewInstance("floor", "floor_" + room.name);
    emit.FloorQuad(M(room.r.x0), M(room.r.y0), M(room.r.x1), M(room.r.y1), 0.0f, floor_color, fid);
    for (const DoorU& d : L.doors) {
      if (d.floor_room != int(r)) continue;
      int t0 = d.t0, t1 = d.t1;
      if (d.closed) t0 = (d.t0 + d.t1) / 2;  // inside half of the entrance only
      if (d.along_x)
        emit.FloorQuad(M(d.o0), M(t0), M(d.o1), M(t1), 0.0f, floor_color, fid);
      else
        emit.FloorQuad(M(t0), M(d.o0), M(t1), M(d.o1), 0.0f, floor_color, fid);
    }
    if (params.ceiling) {
      const uint32_t cid = emit.NewInstance("ceiling", "ceiling_" + room.name);
      emit.CeilingQuad(M(room.r.x0), M(room.r.y0), M(room.r.x1), M(room.r.y1), H,
                       Color{245, 245, 242}, cid);
    }
    Room out;
    out.name = room.name;
    out.footprint_W = Eigen::AlignedBox2f(Eigen::Vector2f(M(room.r.x0), M(room.r.y0)),
                                          Eigen::Vector2f(M(room.r.x1), M(room.r.y1)));
    world.rooms.push_back(out);
  }

  if (params.furniture) {
    Catalogue catalogue(&rng, &index, params.mesh_probability, params.max_mesh_triangles);
    Furnisher furnisher{rng, catalogue};
    for (size_t r = 0; r < L.rooms.size(); ++r) {
      const RoomU& room = L.rooms[r];
      std::vector<DoorSide> sides;
      for (const DoorU& d : L.doors) {
        if (d.room_a != int(r) && d.room_b != int(r)) continue;
        DoorSide s;
        s.o0 = M(d.o0);
        s.o1 = M(d.o1);
        if (d.along_x)
          s.side = d.t0 >= room.r.y1 ? 0 : 2;
        else
          s.side = d.t0 >= room.r.x1 ? 3 : 1;
        sides.push_back(s);
      }
      FurnishRoom(room, sides, furnisher, rng, emit);
    }
    if (!catalogue.status().ok()) return catalogue.status();
  }

  // A random mirror in x and / or y (triangles re-wound so faces still point outwards).
  const bool mx = rng.Chance(0.5), my = rng.Chance(0.5);
  const float W = M(L.W), D = M(L.D);
  for (V3& p : world.mesh.positions) {
    if (mx) p.x() = W - p.x();
    if (my) p.y() = D - p.y();
  }
  if (mx != my)
    for (auto& t : world.mesh.triangles) std::swap(t[1], t[2]);
  for (Room& room : world.rooms) {
    Eigen::Vector2f lo = room.footprint_W.min(), hi = room.footprint_W.max();
    if (mx) std::tie(lo.x(), hi.x()) = std::make_pair(W - hi.x(), W - lo.x());
    if (my) std::tie(lo.y(), hi.y()) = std::make_pair(D - hi.y(), D - lo.y());
    room.footprint_W = Eigen::AlignedBox2f(lo, hi);
  }
  ComputeInstanceBounds(&world);
  return world;
}

Result<ApartmentSize> ParseApartmentSize(const std::string& text) {
  if (text == "S" || text == "s") return ApartmentSize::kS;
  if (text == "M" || text == "m") return ApartmentSize::kM;
  if (text == "L" || text == "l") return ApartmentSize::kL;
  return InvalidArgument("apartment size must be S, M or L, got '" + text + "'");
}

const char* ApartmentSizeName(ApartmentSize size) {
  return size == ApartmentSize::kS ? "S" : size == ApartmentSize::kM ? "M" : "L";
}

}  // namespace voxplan
