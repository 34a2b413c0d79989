#pragma once
// What the apartment generator's stages share (layout -> walls, floors, ceilings -> furniture
// room by room): the random stream, the integer layout, furniture items and the mesh emitter.
// Internal to sim/apartment*; sim/apartment.h is the public face.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/status.h"
#include "sim/apartment.h"
#include "sim/scene_loader.h"
#include "sim/world.h"

namespace voxplan::apartment {

using Color = std::array<uint8_t, 3>;
using V3 = Eigen::Vector3f;

// The layout grid. Layout lengths are ints in these units; a `_u` suffix names such a length.
constexpr double kUnitM = 0.05;
constexpr double kPi = 3.14159265358979323846;
inline float Metres(int length_u) { return float(double(length_u) * kUnitM); }

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

inline Color Jitter(Color c, Rng& rng, int amount = 12) {
  for (auto& v : c) v = uint8_t(std::clamp(int(v) + rng.Int(-amount, amount), 0, 255));
  return c;
}

// Furniture colours; the entrance door slab is kDarkWood too.
inline constexpr Color kWood{150, 105, 65}, kDarkWood{95, 65, 40}, kWhite{235, 235, 232},
    kFabric{90, 110, 140}, kMetal{160, 165, 170}, kBlack{30, 30, 32}, kCeramic{245, 245, 245};

// ---------------------------------------------------------------------------------------------
// The layout (layout.cpp), every length in layout units.

struct GridRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

struct GridDoor {
  bool along_x = true;  // the wall runs along x; the opening is an x interval
  int o0 = 0, o1 = 0;   // opening along the wall
  int t0 = 0, t1 = 0;   // the wall's thickness range (y for along_x walls)
  int height = 42;      // 2.1 m
  bool closed = false;  // the entrance: a door slab fills the opening
  int room_a = -1, room_b = -1;
  int floor_room = -1;  // whose floor covers the threshold
};

struct GridWall {
  bool along_x = true;
  int a0 = 0, a1 = 0;  // extent along the wall
  int t0 = 0, t1 = 0;  // thickness range
  std::vector<int> doors;
};

struct GridRoom {
  std::string name, type;
  GridRect r;
};

struct GridLayout {
  int width_u = 0, depth_u = 0, height_u = 52;  // gross x and y extents, wall height
  std::vector<GridRoom> rooms;
  std::vector<GridWall> walls;
  std::vector<GridDoor> doors;
};

// Draws the rectangle, the corridor, the room program and the doors (see sim/apartment.h).
GridLayout MakeLayout(ApartmentSize size, Rng& rng);

// ---------------------------------------------------------------------------------------------
// Furniture items (furniture.cpp): parametric parts or a visual mesh, and groups of items.

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

// (x, y) turned by q quarter turns counter-clockwise.
inline Eigen::Vector2f Rot(int q, float x, float y) {
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

// The furniture models of the index, read on first use, drawn with the mesh probability and
// charged against the triangle budget.
class Catalogue {
 public:
  Catalogue(Rng* rng, const std::vector<FurnitureModel>* index, float probability, int budget)
      : rng_(*rng), index_(index), probability_(probability), budget_(budget) {}
  const Status& status() const { return status_; }
  int mesh_triangles() const { return used_; }
  void Charge(int triangles) { used_ += triangles; }

  // A mesh for `model`, or null (no index, not drawn, over budget, or unreadable).
  const PreparedMesh* Mesh(const std::string& model, bool force = false);

  static Item MeshItem(const std::string& cls, const std::string& model, const PreparedMesh* m);

 private:
  Rng& rng_;
  const std::vector<FurnitureModel>* index_;
  float probability_;
  int budget_;
  int used_ = 0;
  std::map<std::string, std::unique_ptr<PreparedMesh>> cache_;
  Status status_;
};

// A parametric item (class, model, mesh stand-in, size, parts) and an item's size
// (furniture.cpp).
struct ItemSpec;
struct ItemSize;

// The item builders: each one a mesh when the catalogue gives one, else parametric.
struct Furnisher {
  Rng& rng;
  Catalogue& cat;

  Item Bed(bool dbl);
  Item Nightstand();
  Item SmallDecor();
  Item Wardrobe();
  Item Shelf();
  Item Chair();
  Item Table(float w, float d, float h, bool round);
  Item Desk();
  Item DeskGroup();
  Item DiningGroup(int chairs_per_side);
  Item Sofa();
  Item Armchair();
  Item CoffeeTable();
  Item SofaGroup();
  Item TvGroup();
  Item Counter(float length);
  Item Fridge();
  Item Bin();
  Item Plant();
  Item Bathtub();
  Item Toilet();
  Item Sink();
  Item ShoeRack();
  Item SideCabinet();
  Item Portrait();
  Item Rug(float max_w, float max_d);

 private:
  // The spec's mesh when the catalogue draws one, else the parametric item at a drawn size.
  Item Build(const ItemSpec& spec);
  // The same with the mesh model chosen by the caller (one of several).
  Item Build(const ItemSpec& spec, const std::string& mesh_model);
  // The parametric item at the given size.
  Item Parametric(const ItemSpec& spec, const ItemSize& size);
};

// ---------------------------------------------------------------------------------------------
// Meshes and instances (emit.cpp).

class Emitter {
 public:
  explicit Emitter(World* world) : world_(world) {}

  uint32_t NewInstance(const std::string& cls, const std::string& model);
  void Quad(const V3& a, const V3& b, const V3& c, const V3& d, Color color, uint32_t id);
  void FloorQuad(float x0, float y0, float x1, float y1, float z, Color c, uint32_t id);
  void CeilingQuad(float x0, float y0, float x1, float y1, float z, Color c, uint32_t id);
  void Box(const V3& lo, const V3& hi, Color c, uint32_t id);
  void Cylinder(float cx, float cy, float r, float z0, float z1, Color c, uint32_t id);
  // The item with its local frame turned by `quarter` and its origin at (x, y, z).
  void Emit(const Item& item, int quarter, float x, float y, float z);

 private:
  World* world_;
};

// Every wall box of the layout, wall by wall.
void EmitWalls(const GridLayout& layout, Emitter& emit, Rng& rng);
// Per room: the floor (interior plus the thresholds it owns), the ceiling when asked, and the
// room's footprint in world->rooms.
void EmitRooms(const GridLayout& layout, bool ceiling, Emitter& emit, Rng& rng, World* world);
// A random mirror in x and / or y of the whole world (triangles re-wound so faces still point
// outwards).
void MirrorWorld(const GridLayout& layout, Rng& rng, World* world);

// ---------------------------------------------------------------------------------------------
// Furniture placement (room_planner.cpp).

// Furnishes every room, in layout order, placing each item so that the room stays navigable.
void FurnishRooms(const GridLayout& layout, Furnisher& furnisher, Rng& rng, Emitter& emit);

}  // namespace voxplan::apartment
