#pragma once
// A seeded procedural apartment: rooms and a corridor with walls, door openings, floor, ceiling
// and furniture, every object an instance with a class. Same params -> same World, bit for bit
// (the generator draws from its own SplitMix64 stream, never from std:: distributions).
//
// Layout (before a random mirror in x and/or y): a rectangle W x D (gross area, outer wall faces
// included, uniform in the size class shrunk by 5 %), exterior walls 0.15 m thick, interior walls
// 0.10 m, height 2.5-2.7 m, every face on the 5 cm grid. One end is a full-depth living block
// (living room; in M and L sometimes split into living + dining/kitchen by a wall with a door);
// the rest is a corridor (1.2-1.5 m) along x with a strip of rooms on each side (kitchen,
// bathroom, bedrooms, study, wc, storage). Every room has a door opening (0.8-0.9 m wide, 2.1 m
// high, with a lintel above) onto the corridor; the corridor opens into the living block over
// its full width; the kitchen, when next to the living block, has a second door into it; a split
// living block has a 1.2 m door between its two rooms. The entrance is a closed door slab in the
// exterior wall, so the inside is sealed from the outside.
//
// Instances (classes): "wall" (one per wall box: segments between openings and lintels),
// "door" (the entrance slab), "floor" (one per room: its interior plus the thresholds of its
// doors), "ceiling" (one per room, a downward-facing quad at the wall height; its own instances
// so that top-down renders can drop class "ceiling"), and furniture: "bed", "nightstand",
// "wardrobe", "desk", "chair", "table", "sofa", "shelf", "cabinet", "tv", "appliance",
// "bathtub", "toilet", "sink", "plant", "carpet", "decor", "bin". Furniture is either parametric
// (boxes and 16-sided cylinders, per-vertex colours) or, when an index is given, a visual mesh
// from it (Bed_01, NightStand_01, Wardrobe_01, ReadingDesk_01, ChairA_01, ChairD_01,
// KitchenTable_01, CoffeeTable_01, Refrigerator_01, TVCabinet_01, TV_01, ShoeRack_01, SofaB_01,
// Trash_01, Vase_01, portraits), rotated by quarter turns only. World::rooms holds the interior
// footprint of every room, corridor included.
//
// Guarantees (checked by tests/sim/test_apartment.cpp through RasterizeFloorPlan): furniture
// stays inside its room's interior (>= 2 cm from wall faces), out of a 1 m deep zone in front of
// every door on both sides, and every placement keeps the room's free space, eroded by 0.2 m and
// by 0.25 m (robot radii), one connected piece that reaches every door. Generating an M
// apartment takes ~0.1 s; triangle counts stay around 10k-50k.
#include <cstdint>
#include <string>

#include "core/status.h"
#include "sim/world.h"

namespace voxplan {

// Gross floor area 60-110, 110-200, 200-350, 300-450 m²; XL is Guo 2022's "large" (over 300).
// R is a single furnished room of 20-70 m² (Xu 2017's scenes, X T1): no corridor, one room.
enum class ApartmentSize { kS, kM, kL, kXL, kR };

struct ApartmentParams {
  ApartmentSize size = ApartmentSize::kM;
  uint64_t seed = 0;
  bool ceiling = true;  // ceiling quads, their own instances (class "ceiling")
  bool furniture = true;
  std::string furniture_index;     // aws_furniture_index.tsv; empty: parametric furniture only
  float mesh_probability = 0.5f;   // chance that a role with a mesh model uses it
  int max_mesh_triangles = 60000;  // mesh furniture budget; parametric beyond it
};

Result<World> GenerateApartment(const ApartmentParams& params);

// "S", "M", "L", "XL", "R" (either case).
Result<ApartmentSize> ParseApartmentSize(const std::string& text);
const char* ApartmentSizeName(ApartmentSize size);
// Gross floor area range of a size class, m².
void ApartmentAreaRange(ApartmentSize size, float* min_m2, float* max_m2);

}  // namespace voxplan
