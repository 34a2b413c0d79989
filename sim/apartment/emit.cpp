// The apartment's geometry into the World: quads, boxes and cylinders with instance ids, the
// walls, floors and ceilings of the layout, furniture items, the rooms' footprints and the final
// mirror. One place writes the mesh, so triangle order and instance ids follow the call order.
#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "sim/apartment/apartment_internal.h"

namespace voxplan::apartment {

uint32_t Emitter::NewInstance(const std::string& cls, const std::string& model) {
  Instance inst;
  inst.id = uint32_t(world_->instances.size() + 1);
  inst.class_name = cls;
  inst.model = model;
  world_->instances.push_back(inst);
  return inst.id;
}

void Emitter::Quad(const V3& a, const V3& b, const V3& c, const V3& d, Color color, uint32_t id) {
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

void Emitter::FloorQuad(float x0, float y0, float x1, float y1, float z, Color c, uint32_t id) {
  Quad({x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}, c, id);
}
void Emitter::CeilingQuad(float x0, float y0, float x1, float y1, float z, Color c, uint32_t id) {
  Quad({x0, y0, z}, {x0, y1, z}, {x1, y1, z}, {x1, y0, z}, c, id);
}

void Emitter::Box(const V3& lo, const V3& hi, Color c, uint32_t id) {
  const float x0 = lo.x(), y0 = lo.y(), z0 = lo.z(), x1 = hi.x(), y1 = hi.y(), z1 = hi.z();
  Quad({x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0}, c, id);  // -z
  Quad({x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}, c, id);  // +z
  Quad({x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}, c, id);  // -y
  Quad({x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}, c, id);  // +y
  Quad({x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}, c, id);  // -x
  Quad({x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}, c, id);  // +x
}

void Emitter::Cylinder(float cx, float cy, float r, float z0, float z1, Color c, uint32_t id) {
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

void Emitter::Emit(const Item& item, int quarter, float x, float y, float z) {
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

namespace {

// The wall boxes of one wall line: segments between openings (full height) and lintels.
void EmitWall(const GridWall& w, const std::vector<GridDoor>& doors, int height_u, Emitter& emit,
              Rng& rng) {
  std::vector<const GridDoor*> openings;
  for (int d : w.doors) openings.push_back(&doors[d]);
  std::sort(openings.begin(), openings.end(),
            [](const GridDoor* a, const GridDoor* b) { return a->o0 < b->o0; });
  const Color wall_color = Jitter({232, 228, 218}, rng, 6);
  auto box = [&](int a0, int a1, int z0, int z1, const char* model) {
    if (a1 <= a0 || z1 <= z0) return;
    const uint32_t id = emit.NewInstance("wall", model);
    if (w.along_x)
      emit.Box({Metres(a0), Metres(w.t0), Metres(z0)}, {Metres(a1), Metres(w.t1), Metres(z1)},
               wall_color, id);
    else
      emit.Box({Metres(w.t0), Metres(a0), Metres(z0)}, {Metres(w.t1), Metres(a1), Metres(z1)},
               wall_color, id);
  };
  int a = w.a0;
  for (const GridDoor* d : openings) {
    box(a, d->o0, 0, height_u, "wall_segment");
    box(d->o0, d->o1, d->height, height_u, "lintel");
    if (d->closed) {
      // The entrance door: a 5 cm slab in the middle of the wall filling the opening.
      const int mid = (w.t0 + w.t1) / 2;
      const uint32_t id = emit.NewInstance("door", "param_door_slab");
      const Color c = Jitter(kDarkWood, rng);
      // 1 cm below the lintel: a slab top flush with the lintel's underside would hide the
      // slab from RasterizeFloorPlan's inside-a-solid test.
      const float top = Metres(d->height) - 0.01f;
      if (w.along_x)
        emit.Box({Metres(d->o0), Metres(mid - 1), 0}, {Metres(d->o1), Metres(mid), top}, c, id);
      else
        emit.Box({Metres(mid - 1), Metres(d->o0), 0}, {Metres(mid), Metres(d->o1), top}, c, id);
    }
    a = d->o1;
  }
  box(a, w.a1, 0, height_u, "wall_segment");
}

}  // namespace

void EmitWalls(const GridLayout& layout, Emitter& emit, Rng& rng) {
  for (const GridWall& w : layout.walls) EmitWall(w, layout.doors, layout.height_u, emit, rng);
}

void EmitRooms(const GridLayout& layout, bool ceiling, Emitter& emit, Rng& rng, World* world) {
  const float height_m = Metres(layout.height_u);
  for (size_t r = 0; r < layout.rooms.size(); ++r) {
    const GridRoom& room = layout.rooms[r];
    const Color floor_color = room.type == "bathroom" || room.type == "wc" || room.type == "kitchen"
                                  ? Jitter({200, 200, 195}, rng, 10)
                                  : Jitter({165, 125, 85}, rng, 15);
    const uint32_t fid = emit.NewInstance("floor", "floor_" + room.name);
    emit.FloorQuad(Metres(room.r.x0), Metres(room.r.y0), Metres(room.r.x1), Metres(room.r.y1), 0.0f,
                   floor_color, fid);
    for (const GridDoor& d : layout.doors) {
      if (d.floor_room != int(r)) continue;
      int t0 = d.t0, t1 = d.t1;
      if (d.closed) t0 = (d.t0 + d.t1) / 2;  // inside half of the entrance only
      if (d.along_x)
        emit.FloorQuad(Metres(d.o0), Metres(t0), Metres(d.o1), Metres(t1), 0.0f, floor_color, fid);
      else
        emit.FloorQuad(Metres(t0), Metres(d.o0), Metres(t1), Metres(d.o1), 0.0f, floor_color, fid);
    }
    if (ceiling) {
      const uint32_t cid = emit.NewInstance("ceiling", "ceiling_" + room.name);
      emit.CeilingQuad(Metres(room.r.x0), Metres(room.r.y0), Metres(room.r.x1), Metres(room.r.y1),
                       height_m, Color{245, 245, 242}, cid);
    }
    Room out;
    out.name = room.name;
    out.footprint_W = Eigen::AlignedBox2f(Eigen::Vector2f(Metres(room.r.x0), Metres(room.r.y0)),
                                          Eigen::Vector2f(Metres(room.r.x1), Metres(room.r.y1)));
    world->rooms.push_back(out);
  }
}

void MirrorWorld(const GridLayout& layout, Rng& rng, World* world) {
  const bool mx = rng.Chance(0.5), my = rng.Chance(0.5);
  const float width_m = Metres(layout.width_u), depth_m = Metres(layout.depth_u);
  for (V3& p : world->mesh.positions) {
    if (mx) p.x() = width_m - p.x();
    if (my) p.y() = depth_m - p.y();
  }
  if (mx != my)
    for (auto& t : world->mesh.triangles) std::swap(t[1], t[2]);
  for (Room& room : world->rooms) {
    Eigen::Vector2f lo = room.footprint_W.min(), hi = room.footprint_W.max();
    if (mx) std::tie(lo.x(), hi.x()) = std::make_pair(width_m - hi.x(), width_m - lo.x());
    if (my) std::tie(lo.y(), hi.y()) = std::make_pair(depth_m - hi.y(), depth_m - lo.y());
    room.footprint_W = Eigen::AlignedBox2f(lo, hi);
  }
}

}  // namespace voxplan::apartment
