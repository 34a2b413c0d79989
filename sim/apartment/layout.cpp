// The apartment's layout on the 5 cm grid: the gross rectangle and its bands, the room program,
// then walls, rooms and doors. Its own stage so that the geometry can be read without the
// furniture; every random draw happens in one fixed order (the worlds depend on it).
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "sim/apartment/apartment_internal.h"

namespace voxplan::apartment {

namespace {

constexpr int kExteriorWallU = 3;    // 0.15 m
constexpr int kInteriorWallU = 2;    // 0.10 m
constexpr int kMinStripDepthU = 48;  // 2.4 m: the shallowest strip of rooms

int Snap(double metres) { return int(std::lround(metres / kUnitM)); }

// The bands of the rectangle. South to north: exterior wall, south strip, interior wall,
// corridor, interior wall, north strip, exterior wall. West to east: exterior wall, the strips
// and the corridor, the separator wall, the living block, exterior wall.
struct Bands {
  int corridor_width_u = 0;
  int corridor_y0_u = 0, corridor_y1_u = 0;
  int north_y0_u = 0, north_y1_u = 0;
  int living_width_u = 0;
  int separator_x_u = 0;  // the separator wall spans [separator_x_u, separator_x_u + interior]
  int living_x0_u = 0, living_x1_u = 0;
  int strip_length_u = 0;  // the strips' (and the corridor's) length along x
};

// Which rooms the strips hold, and whether the living block is split.
struct RoomProgram {
  bool split_living = false;       // a wall with a door splits the living block in two rooms
  bool kitchen_in_living = false;  // the split-off room is the kitchen (else a dining room)
  int rooms_north = 0, rooms_south = 0;
  std::vector<std::string> types;  // north strip west -> east, then south strip west -> east
};

// The walls that doors are attached to later.
struct FixedWalls {
  int west = -1, separator = -1, corridor_south = -1, corridor_north = -1;
};

// The living block's room and the room split off it (-1 when not split).
struct LivingBlock {
  int living = -1, other = -1;
};

double WidthWeight(const std::string& type) {
  if (type == "wc" || type == "storage") return 0.55;
  if (type == "bathroom") return 0.75;
  if (type == "kitchen") return 1.1;
  if (type == "study") return 0.9;
  return 1.2;
}

int MinWidthU(const std::string& type) {
  if (type == "wc" || type == "storage") return 32;
  if (type == "bathroom") return 38;
  return 50;
}

int AddRoom(GridLayout* layout, const std::string& type, GridRect r) {
  GridRoom room;
  room.type = type;
  room.r = r;
  layout->rooms.push_back(room);
  return int(layout->rooms.size()) - 1;
}

int AddDoor(GridLayout* layout, GridDoor door) {
  layout->doors.push_back(door);
  return int(layout->doors.size()) - 1;
}

// A wall with fixed extents; doors are attached to it later.
int AddWall(GridLayout* layout, bool along_x, int a0, int a1, int t0, int t1) {
  layout->walls.push_back({along_x, a0, a1, t0, t1, {}});
  return int(layout->walls.size()) - 1;
}

// The gross rectangle (its area uniform in the size class shrunk by 5 %) and the wall height.
// The corridor's width is drawn between the two, so it is drawn here and returned.
int DrawOutline(ApartmentSize size, Rng& rng, GridLayout* layout) {
  float lo_m2, hi_m2;
  ApartmentAreaRange(size, &lo_m2, &hi_m2);
  const double margin_m2 = 0.05 * (hi_m2 - lo_m2);
  const double area_m2 = rng.Uniform(lo_m2 + margin_m2, hi_m2 - margin_m2);
  layout->height_u = 50 + rng.Int(0, 4);  // 2.50 .. 2.70 m
  const int corridor_width_u = rng.Int(24, 30);
  const double min_depth_m =
      (2 * kExteriorWallU + 2 * kInteriorWallU + corridor_width_u + 2 * kMinStripDepthU) * kUnitM;
  // Depth ranges per class, S M L XL (XL: about as deep as L, a third wider).
  constexpr double kDepthLoM[] = {6.6, 7.6, 9.6, 11.0};
  constexpr double kDepthHiM[] = {8.0, 10.4, 13.4, 15.0};
  double depth_lo_m = kDepthLoM[int(size)];
  double depth_hi_m = kDepthHiM[int(size)];
  depth_lo_m = std::max({depth_lo_m, min_depth_m, std::sqrt(area_m2 / 2.3)});
  depth_hi_m = std::max(depth_lo_m, std::min(depth_hi_m, std::sqrt(area_m2 / 1.15)));
  layout->depth_u = Snap(rng.Uniform(depth_lo_m, depth_hi_m));
  layout->width_u = Snap(area_m2 / (layout->depth_u * kUnitM));
  return corridor_width_u;
}

Bands DrawBands(const GridLayout& layout, int corridor_width_u, Rng& rng) {
  const int width_u = layout.width_u, depth_u = layout.depth_u;
  Bands bands;
  bands.corridor_width_u = corridor_width_u;
  // y: south strip, corridor, north strip.
  const int strips_depth_u = depth_u - 2 * kExteriorWallU - 2 * kInteriorWallU - corridor_width_u;
  int south_depth_u = int(std::lround(strips_depth_u * rng.Uniform(0.42, 0.58)));
  south_depth_u = std::clamp(south_depth_u, kMinStripDepthU, strips_depth_u - kMinStripDepthU);
  bands.corridor_y0_u = kExteriorWallU + south_depth_u + kInteriorWallU;
  bands.corridor_y1_u = bands.corridor_y0_u + corridor_width_u;
  bands.north_y0_u = bands.corridor_y1_u + kInteriorWallU;
  bands.north_y1_u = depth_u - kExteriorWallU;
  // x: west part (strips + corridor), separator wall, living block.
  int living_width_u = int(std::lround(width_u * rng.Uniform(0.26, 0.34)));
  living_width_u = std::max(living_width_u, 66);
  bands.living_width_u = living_width_u;
  bands.separator_x_u = width_u - kExteriorWallU - living_width_u - kInteriorWallU;
  bands.living_x0_u = bands.separator_x_u + kInteriorWallU;
  bands.living_x1_u = width_u - kExteriorWallU;
  bands.strip_length_u = bands.separator_x_u - kExteriorWallU;
  return bands;
}

// The room program: whether the living block is split, how many rooms each strip holds and of
// which types.
RoomProgram DrawProgram(ApartmentSize size, const GridLayout& layout, const Bands& bands,
                        Rng& rng) {
  RoomProgram program;
  const bool split_living =
      size != ApartmentSize::kS &&
      bands.living_width_u * (layout.depth_u - 2 * kExteriorWallU) * kUnitM * kUnitM > 38.0 &&
      rng.Chance(0.6);
  const bool kitchen_in_living = split_living && rng.Chance(0.5);
  program.split_living = split_living;
  program.kitchen_in_living = kitchen_in_living;
  std::vector<std::string> extra_types = {"bedroom", "bedroom", "study",
                                          "wc",      "storage", "bedroom"};
  if (size == ApartmentSize::kL || size == ApartmentSize::kXL)
    extra_types = {"bedroom", "bedroom", "bathroom", "study", "bedroom",
                   "wc",      "storage", "bedroom",  "study"};
  if (size == ApartmentSize::kXL)
    extra_types.insert(extra_types.end(), {"bathroom", "bedroom", "storage"});
  if (size == ApartmentSize::kS) extra_types = {"bedroom", "study", "storage"};

  const int strip_length_u = bands.strip_length_u;
  auto rooms_in_strip = [&](double per_room_m) {
    return std::clamp(int(std::lround(strip_length_u * kUnitM / per_room_m)), 1, 6);
  };
  int rooms_north = rooms_in_strip(rng.Uniform(3.3, 4.3));
  int rooms_south = rooms_in_strip(rng.Uniform(3.3, 4.3));
  // At least a bathroom and a bedroom, plus the kitchen when it is not in the living block.
  const int min_slots = kitchen_in_living ? 2 : 3;
  if (rooms_north + rooms_south < min_slots) rooms_south = min_slots - rooms_north;

  // Slots: north strip west -> east, then south strip west -> east. The kitchen (unless in the
  // living block) takes the north slot next to the living block.
  std::vector<std::string>& types = program.types;
  for (int attempt = 0;; ++attempt) {
    const int slots = rooms_north + rooms_south;
    std::vector<std::string> shuffled = {"bathroom", "bedroom"};
    for (size_t i = 0;
         shuffled.size() + (kitchen_in_living ? 0 : 1) < size_t(slots) && i < extra_types.size();
         ++i)
      shuffled.push_back(extra_types[i]);
    while (shuffled.size() + (kitchen_in_living ? 0 : 1) < size_t(slots))
      shuffled.push_back("bedroom");
    rng.Shuffle(&shuffled);
    types.assign(slots, "");
    size_t k = 0;
    for (int s = 0; s < slots; ++s) {
      if (!kitchen_in_living && s == rooms_north - 1)
        types[s] = "kitchen";
      else
        types[s] = shuffled[k++];
    }
    // Widths per strip; shrink the strip's room count while a room would be too narrow.
    bool ok = true;
    for (int strip = 0; strip < 2 && ok; ++strip) {
      const int first = strip == 0 ? 0 : rooms_north, n = strip == 0 ? rooms_north : rooms_south;
      double weight_sum = 0.0;
      for (int i = 0; i < n; ++i) weight_sum += WidthWeight(types[first + i]);
      const int usable_u = strip_length_u - (n - 1) * kInteriorWallU;
      for (int i = 0; i < n; ++i)
        if (usable_u * WidthWeight(types[first + i]) / weight_sum < MinWidthU(types[first + i]) + 2)
          ok = false;
      if (!ok) {
        if (rooms_north + rooms_south <= min_slots) {
          ok = true;  // keep the program; rooms are narrower than wished
        } else if (strip == 0 && rooms_north > 1) {
          --rooms_north;
        } else if (rooms_south > 1) {
          --rooms_south;
        } else if (rooms_north > 1) {
          --rooms_north;
        }
      }
    }
    if (ok || attempt > 20) break;
  }
  program.rooms_north = rooms_north;
  program.rooms_south = rooms_south;
  return program;
}

FixedWalls AddFixedWalls(const Bands& bands, GridLayout* layout) {
  const int width_u = layout->width_u, depth_u = layout->depth_u;
  const int separator_x_u = bands.separator_x_u;
  FixedWalls walls;
  AddWall(layout, true, 0, width_u, 0, kExteriorWallU);                  // south exterior
  AddWall(layout, true, 0, width_u, depth_u - kExteriorWallU, depth_u);  // north exterior
  walls.west = AddWall(layout, false, kExteriorWallU, depth_u - kExteriorWallU, 0, kExteriorWallU);
  AddWall(layout, false, kExteriorWallU, depth_u - kExteriorWallU, width_u - kExteriorWallU,
          width_u);  // east exterior
  walls.separator = AddWall(layout, false, kExteriorWallU, depth_u - kExteriorWallU, separator_x_u,
                            separator_x_u + kInteriorWallU);
  walls.corridor_south = AddWall(layout, true, kExteriorWallU, separator_x_u,
                                 bands.corridor_y0_u - kInteriorWallU, bands.corridor_y0_u);
  walls.corridor_north = AddWall(layout, true, kExteriorWallU, separator_x_u, bands.corridor_y1_u,
                                 bands.corridor_y1_u + kInteriorWallU);
  return walls;
}

// The strip rooms west to east, each with its door onto the corridor and a wall to the next.
// Returns the kitchen's room, or -1 when the kitchen is not in a strip.
int AddStripRooms(const Bands& bands, const RoomProgram& program, int corridor,
                  const FixedWalls& walls, Rng& rng, GridLayout* layout) {
  int kitchen_room = -1;
  for (int strip = 0; strip < 2; ++strip) {
    const int first = strip == 0 ? 0 : program.rooms_north,
              n = strip == 0 ? program.rooms_north : program.rooms_south;
    const int y0_u = strip == 0 ? bands.north_y0_u : kExteriorWallU,
              y1_u = strip == 0 ? bands.north_y1_u : bands.corridor_y0_u - kInteriorWallU;
    double weight_sum = 0.0;
    std::vector<double> weights;
    for (int i = 0; i < n; ++i) {
      weights.push_back(WidthWeight(program.types[first + i]) * rng.Uniform(0.92, 1.08));
      weight_sum += weights.back();
    }
    const int usable_u = bands.strip_length_u - (n - 1) * kInteriorWallU;
    int x_u = kExteriorWallU, used_u = 0;
    for (int i = 0; i < n; ++i) {
      const int room_width_u =
          i == n - 1 ? usable_u - used_u : int(std::floor(usable_u * weights[i] / weight_sum));
      used_u += room_width_u;
      const std::string& type = program.types[first + i];
      const int room = AddRoom(layout, type, {x_u, y0_u, x_u + room_width_u, y1_u});
      if (type == "kitchen") kitchen_room = room;
      // Door onto the corridor.
      GridDoor door;
      door.along_x = true;
      const int door_width_u = (type == "bathroom" || type == "wc" || type == "storage") ? 16 : 18;
      const int door_lo_u = x_u + 3,
                door_hi_u = std::max(door_lo_u, x_u + room_width_u - 3 - door_width_u);
      door.o0 = rng.Int(door_lo_u, door_hi_u);
      door.o1 = door.o0 + door_width_u;
      door.t0 = strip == 0 ? bands.corridor_y1_u : bands.corridor_y0_u - kInteriorWallU;
      door.t1 = door.t0 + kInteriorWallU;
      door.room_a = room;
      door.room_b = corridor;
      door.floor_room = room;
      layout->walls[strip == 0 ? walls.corridor_north : walls.corridor_south].doors.push_back(
          AddDoor(layout, door));
      if (i + 1 < n)
        AddWall(layout, false, y0_u, y1_u, x_u + room_width_u, x_u + room_width_u + kInteriorWallU);
      x_u += room_width_u + kInteriorWallU;
    }
  }
  return kitchen_room;
}

// The living block, maybe split along the corridor's north or south wall line. A split-off
// kitchen becomes *kitchen_room.
LivingBlock AddLivingBlock(const Bands& bands, const RoomProgram& program, Rng& rng,
                           int* kitchen_room, GridLayout* layout) {
  const int depth_u = layout->depth_u;
  const int x0_u = bands.living_x0_u, x1_u = bands.living_x1_u;
  LivingBlock block;
  if (program.split_living) {
    const bool other_north = rng.Chance(0.5);
    const std::string other_type = program.kitchen_in_living ? "kitchen" : "dining";
    if (other_north) {
      block.living = AddRoom(layout, "living", {x0_u, kExteriorWallU, x1_u, bands.corridor_y1_u});
      block.other =
          AddRoom(layout, other_type,
                  {x0_u, bands.corridor_y1_u + kInteriorWallU, x1_u, depth_u - kExteriorWallU});
    } else {
      block.living =
          AddRoom(layout, "living", {x0_u, bands.corridor_y0_u, x1_u, depth_u - kExteriorWallU});
      block.other = AddRoom(layout, other_type,
                            {x0_u, kExteriorWallU, x1_u, bands.corridor_y0_u - kInteriorWallU});
    }
    if (program.kitchen_in_living) *kitchen_room = block.other;
    const int split_y_u = other_north ? bands.corridor_y1_u : bands.corridor_y0_u - kInteriorWallU;
    const int split_wall = AddWall(layout, true, x0_u, x1_u, split_y_u, split_y_u + kInteriorWallU);
    GridDoor door;
    door.along_x = true;
    const int door_width_u = 24;
    door.o0 = rng.Int(x0_u + 3, std::max(x0_u + 3, x1_u - 3 - door_width_u));
    door.o1 = door.o0 + door_width_u;
    door.t0 = split_y_u;
    door.t1 = split_y_u + kInteriorWallU;
    door.room_a = block.other;
    door.room_b = block.living;
    door.floor_room = block.other;
    layout->walls[split_wall].doors.push_back(AddDoor(layout, door));
  } else {
    block.living =
        AddRoom(layout, "living", {x0_u, kExteriorWallU, x1_u, depth_u - kExteriorWallU});
  }
  return block;
}

// The entrance: a closed door slab in the west exterior wall, opening [o0_u, o0_u + width_u)
// along it, into `room`.
void AddEntrance(GridLayout* layout, int west_wall, int room, int o0_u, int width_u) {
  GridDoor door;
  door.along_x = false;
  door.o0 = o0_u;
  door.o1 = o0_u + width_u;
  door.t0 = 0;
  door.t1 = kExteriorWallU;
  door.closed = true;
  door.room_a = room;
  door.floor_room = room;
  layout->walls[west_wall].doors.push_back(AddDoor(layout, door));
}

// The corridor's opening into the living block, the strip kitchen's second door and the
// entrance.
void AddCorridorDoors(const Bands& bands, int corridor, int kitchen_room, const LivingBlock& block,
                      const FixedWalls& walls, Rng& rng, GridLayout* layout) {
  const int separator_x_u = bands.separator_x_u;
  // Corridor -> living block: the corridor's full width.
  {
    GridDoor door;
    door.along_x = false;
    door.o0 = bands.corridor_y0_u;
    door.o1 = bands.corridor_y1_u;
    door.t0 = separator_x_u;
    door.t1 = separator_x_u + kInteriorWallU;
    door.room_a = corridor;
    door.room_b = block.living;
    door.floor_room = corridor;
    layout->walls[walls.separator].doors.push_back(AddDoor(layout, door));
  }
  // Kitchen in the north strip next to the living block: a second door into the block.
  if (kitchen_room >= 0 && layout->rooms[kitchen_room].r.x1 == separator_x_u) {
    const GridRect& kitchen = layout->rooms[kitchen_room].r;
    int east_room = block.living;
    if (block.other >= 0 && layout->rooms[block.other].r.y0 <= kitchen.y0 &&
        layout->rooms[block.other].r.y1 >= kitchen.y1)
      east_room = block.other;
    GridDoor door;
    door.along_x = false;
    const int door_width_u = 18;
    door.o0 = rng.Int(kitchen.y0 + 3, std::max(kitchen.y0 + 3, kitchen.y1 - 3 - door_width_u));
    door.o1 = door.o0 + door_width_u;
    door.t0 = separator_x_u;
    door.t1 = separator_x_u + kInteriorWallU;
    door.room_a = kitchen_room;
    door.room_b = east_room;
    door.floor_room = kitchen_room;
    layout->walls[walls.separator].doors.push_back(AddDoor(layout, door));
  }
  // The entrance: a closed door in the west wall at the corridor.
  const int door_width_u = std::min(20, bands.corridor_width_u - 2);
  AddEntrance(layout, walls.west, corridor,
              rng.Int(bands.corridor_y0_u + 1, bands.corridor_y1_u - 1 - door_width_u),
              door_width_u);
}

// Names: bedroom_1, bedroom_2, ... where a type repeats.
void NameRooms(GridLayout* layout) {
  std::map<std::string, int> counts;
  for (const GridRoom& room : layout->rooms) ++counts[room.type];
  std::map<std::string, int> seen;
  for (GridRoom& room : layout->rooms)
    room.name =
        counts[room.type] > 1 ? room.type + "_" + std::to_string(++seen[room.type]) : room.type;
}

// A single room (size R, Xu 2017's scenes): four exterior walls around one furnished room of a
// drawn type, the closed entrance in the west wall. Its own draws, after the outline's.
GridLayout MakeRoomLayout(Rng& rng) {
  GridLayout layout;
  float lo_m2, hi_m2;
  ApartmentAreaRange(ApartmentSize::kR, &lo_m2, &hi_m2);
  const double margin_m2 = 0.05 * (hi_m2 - lo_m2);
  const double area_m2 = rng.Uniform(lo_m2 + margin_m2, hi_m2 - margin_m2);
  layout.height_u = 50 + rng.Int(0, 4);  // 2.50 .. 2.70 m
  // Aspect 1:1 to 2:1, the depth (y) the short side.
  const double depth_m = std::sqrt(area_m2 / rng.Uniform(1.0, 2.0));
  layout.depth_u = Snap(depth_m);
  layout.width_u = Snap(area_m2 / (layout.depth_u * kUnitM));
  const int width_u = layout.width_u, depth_u = layout.depth_u;
  AddWall(&layout, true, 0, width_u, 0, kExteriorWallU);                  // south
  AddWall(&layout, true, 0, width_u, depth_u - kExteriorWallU, depth_u);  // north
  const int west =
      AddWall(&layout, false, kExteriorWallU, depth_u - kExteriorWallU, 0, kExteriorWallU);
  AddWall(&layout, false, kExteriorWallU, depth_u - kExteriorWallU, width_u - kExteriorWallU,
          width_u);  // east
  static const char* const kTypes[] = {"living", "study", "bedroom", "dining"};
  const int room =
      AddRoom(&layout, kTypes[rng.Int(0, 3)],
              {kExteriorWallU, kExteriorWallU, width_u - kExteriorWallU, depth_u - kExteriorWallU});
  const int door_width_u = 18;
  const int interior_u = depth_u - 2 * kExteriorWallU;
  AddEntrance(&layout, west, room,
              kExteriorWallU + rng.Int(4, std::max(4, interior_u - 4 - door_width_u)),
              door_width_u);
  NameRooms(&layout);
  return layout;
}

}  // namespace

GridLayout MakeLayout(ApartmentSize size, Rng& rng) {
  if (size == ApartmentSize::kR) return MakeRoomLayout(rng);
  GridLayout layout;
  const int corridor_width_u = DrawOutline(size, rng, &layout);
  const Bands bands = DrawBands(layout, corridor_width_u, rng);
  const RoomProgram program = DrawProgram(size, layout, bands, rng);
  const FixedWalls walls = AddFixedWalls(bands, &layout);
  const int corridor =
      AddRoom(&layout, "corridor",
              {kExteriorWallU, bands.corridor_y0_u, bands.separator_x_u, bands.corridor_y1_u});
  int kitchen_room = AddStripRooms(bands, program, corridor, walls, rng, &layout);
  const LivingBlock block = AddLivingBlock(bands, program, rng, &kitchen_room, &layout);
  AddCorridorDoors(bands, corridor, kitchen_room, block, walls, rng, &layout);
  NameRooms(&layout);
  return layout;
}

}  // namespace voxplan::apartment
