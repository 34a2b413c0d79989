// Furniture placement, room by room: what each room type gets, and where it goes on a 5 cm
// occupancy grid that keeps the room navigable for the robots. Apart from the item builders so
// that the rules of placement read on their own.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/apartment/apartment_internal.h"

namespace voxplan::apartment {

namespace {

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
  RoomPlanner(const GridRect& r, const std::vector<DoorSide>& doors)
      : x0_(Metres(r.x0)), y0_(Metres(r.y0)), x1_(Metres(r.x1)), y1_(Metres(r.y1)), doors_(doors) {
    pad_ = int(std::ceil(kRobotRadius / kUnitM)) + 2;
    gw_ = (r.x1 - r.x0) + 2 * pad_;
    gh_ = (r.y1 - r.y0) + 2 * pad_;
    ox_ = x0_ - float(pad_ * kUnitM);
    oy_ = y0_ - float(pad_ * kUnitM);
    blocked_.assign(size_t(gw_) * gh_, 0);
    reserved_.assign(blocked_.size(), 0);
    for (int k = 0; k < 2; ++k) {
      inflated_[k].assign(blocked_.size(), 0);
      const int rc = int(std::ceil(kRobotRadii[k] / kUnitM));
      for (int dj = -rc; dj <= rc; ++dj)
        for (int di = -rc; di <= rc; ++di) {
          const double dx = std::max(0.0, std::abs(di) - 0.5);
          const double dy = std::max(0.0, std::abs(dj) - 0.5);
          if (std::hypot(dx, dy) * kUnitM < kRobotRadii[k]) offsets_[k].push_back({di, dj});
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
          const float cx = ox_ + float((i + 0.5) * kUnitM), cy = oy_ + float((j + 0.5) * kUnitM);
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
    *i0 = std::max(0, int(std::floor((r.x0 - ox_) / kUnitM + eps)));
    *j0 = std::max(0, int(std::floor((r.y0 - oy_) / kUnitM + eps)));
    *i1 = std::min(gw_ - 1, int(std::ceil((r.x1 - ox_) / kUnitM - eps)) - 1);
    *j1 = std::min(gh_ - 1, int(std::ceil((r.y1 - oy_) / kUnitM - eps)) - 1);
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
      const int i = int(std::floor((x - ox_) / kUnitM)), j = int(std::floor((y - oy_) / kUnitM));
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

void FurnishRoom(const GridRoom& room, const std::vector<DoorSide>& doors, Furnisher& f, Rng& rng,
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

}  // namespace

void FurnishRooms(const GridLayout& layout, Furnisher& furnisher, Rng& rng, Emitter& emit) {
  for (size_t r = 0; r < layout.rooms.size(); ++r) {
    const GridRoom& room = layout.rooms[r];
    std::vector<DoorSide> sides;
    for (const GridDoor& d : layout.doors) {
      if (d.room_a != int(r) && d.room_b != int(r)) continue;
      DoorSide s;
      s.o0 = Metres(d.o0);
      s.o1 = Metres(d.o1);
      if (d.along_x)
        s.side = d.t0 >= room.r.y1 ? 0 : 2;
      else
        s.side = d.t0 >= room.r.x1 ? 3 : 1;
      sides.push_back(s);
    }
    FurnishRoom(room, sides, furnisher, rng, emit);
  }
}

}  // namespace voxplan::apartment
