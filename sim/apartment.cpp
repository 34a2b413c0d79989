// The apartment generator's entry point: the stages of sim/apartment/ in their fixed order
// (layout, walls, floors and ceilings, furniture, mirror), all drawing from one seeded stream.
#include "sim/apartment.h"

#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "sim/apartment/apartment_internal.h"
#include "sim/scene_loader.h"

namespace voxplan {

namespace {

// One row per ApartmentSize, in its order: the name and the gross floor area range.
struct SizeClass {
  const char* name;
  const char* lower_name;  // also accepted
  float min_m2, max_m2;
};
constexpr SizeClass kSizeClasses[] = {{"S", "s", 60.0f, 110.0f},
                                      {"M", "m", 110.0f, 200.0f},
                                      {"L", "l", 200.0f, 350.0f},
                                      {"XL", "xl", 300.0f, 450.0f},
                                      {"R", "r", 20.0f, 70.0f}};
static_assert(std::size(kSizeClasses) == size_t(ApartmentSize::kR) + 1);

const SizeClass& ClassOf(ApartmentSize size) { return kSizeClasses[int(size)]; }

}  // namespace

void ApartmentAreaRange(ApartmentSize size, float* min_m2, float* max_m2) {
  *min_m2 = ClassOf(size).min_m2;
  *max_m2 = ClassOf(size).max_m2;
}

Result<World> GenerateApartment(const ApartmentParams& params) {
  using namespace apartment;
  if (!(params.mesh_probability >= 0.0f && params.mesh_probability <= 1.0f))
    return InvalidArgument("mesh_probability must be in [0, 1]");
  std::vector<FurnitureModel> index;
  if (params.furniture && !params.furniture_index.empty()) {
    Result<std::vector<FurnitureModel>> read = ReadFurnitureIndex(params.furniture_index);
    if (!read.ok()) return read.status();
    index = std::move(read.value());
  }
  Rng rng(params.seed);
  const GridLayout layout = MakeLayout(params.size, rng);

  World world;
  world.name = std::string("apartment_") + ApartmentSizeName(params.size) + "_seed" +
               std::to_string(params.seed);
  Emitter emit(&world);
  EmitWalls(layout, emit, rng);
  // Floors (room interior + the thresholds it owns) and ceilings, one instance each per room.
  EmitRooms(layout, params.ceiling, emit, rng, &world);

  if (params.furniture) {
    Catalogue catalogue(&rng, &index, params.mesh_probability, params.max_mesh_triangles);
    Furnisher furnisher{rng, catalogue};
    FurnishRooms(layout, furnisher, rng, emit);
    if (!catalogue.status().ok()) return catalogue.status();
  }

  MirrorWorld(layout, rng, &world);
  ComputeInstanceBounds(&world);
  return world;
}

Result<ApartmentSize> ParseApartmentSize(const std::string& text) {
  for (int i = 0; i < int(std::size(kSizeClasses)); ++i) {
    if (text == kSizeClasses[i].name || text == kSizeClasses[i].lower_name) {
      return ApartmentSize(i);
    }
  }
  return InvalidArgument("apartment size must be S, M, L, XL or R, got '" + text + "'");
}

const char* ApartmentSizeName(ApartmentSize size) { return ClassOf(size).name; }

}  // namespace voxplan
