// The apartment generator's entry point: the stages of sim/apartment/ in their fixed order
// (layout, walls, floors and ceilings, furniture, mirror), all drawing from one seeded stream.
#include "sim/apartment.h"

#include <string>
#include <utility>
#include <vector>

#include "sim/apartment/apartment_internal.h"
#include "sim/scene_loader.h"

namespace voxplan {

void ApartmentAreaRange(ApartmentSize size, float* min_m2, float* max_m2) {
  switch (size) {
    case ApartmentSize::kS:
      *min_m2 = 60.0f, *max_m2 = 110.0f;
      break;
    case ApartmentSize::kM:
      *min_m2 = 110.0f, *max_m2 = 200.0f;
      break;
    case ApartmentSize::kL:
      *min_m2 = 200.0f, *max_m2 = 350.0f;
      break;
    default:
      *min_m2 = 300.0f, *max_m2 = 450.0f;
      break;
  }
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
  if (text == "S" || text == "s") return ApartmentSize::kS;
  if (text == "M" || text == "m") return ApartmentSize::kM;
  if (text == "L" || text == "l") return ApartmentSize::kL;
  if (text == "XL" || text == "xl") return ApartmentSize::kXL;
  return InvalidArgument("apartment size must be S, M, L or XL, got '" + text + "'");
}

const char* ApartmentSizeName(ApartmentSize size) {
  switch (size) {
    case ApartmentSize::kS:
      return "S";
    case ApartmentSize::kM:
      return "M";
    case ApartmentSize::kL:
      return "L";
    default:
      return "XL";
  }
}

}  // namespace voxplan
