// The furniture: the catalogue of visual meshes and the item builders. Each parametric item is
// one ItemSpec (class, model, size, parts) made by one builder, so the shape of an item is
// written once; an item draws its size first, then its colours in part order.
#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "io/mesh_io.h"
#include "sim/apartment/apartment_internal.h"

namespace voxplan::apartment {

namespace {

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

}  // namespace

const PreparedMesh* Catalogue::Mesh(const std::string& model, bool force) {
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

Item Catalogue::MeshItem(const std::string& cls, const std::string& model, const PreparedMesh* m) {
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

// ---------------------------------------------------------------------------------------------
// Parametric items.

// An item's local extents: x (width), y (depth, back at +y), z (height).
struct ItemSize {
  float w = 0, d = 0, h = 0;
};

// One extent of an item: fixed, or drawn uniform in [lo, hi) (as a double, then rounded).
struct Extent {
  constexpr Extent(float fixed = 0) : fixed_m(fixed) {}
  constexpr Extent(double lo, double hi) : drawn(true), lo_m(lo), hi_m(hi) {}
  float Draw(Rng& rng) const { return drawn ? float(rng.Uniform(lo_m, hi_m)) : fixed_m; }

  bool drawn = false;
  float fixed_m = 0;
  double lo_m = 0, hi_m = 0;
};

// A parametric item: its class and model, the visual mesh that may stand in for it, its size
// (w, d, h drawn in that order; draw_size instead where they are not independent; neither where
// the caller gives the size) and its parts. `parts` draws the colours and makes the boxes and
// cylinders of an item whose size is set.
struct ItemSpec {
  const char* cls;
  const char* model;
  const char* mesh_model = nullptr;
  Extent w = {}, d = {}, h = {};
  ItemSize (*draw_size)(Rng& rng) = nullptr;
  bool walkable = false;
  std::vector<Part> (*parts)(const Item& it, Rng& rng) = nullptr;
};

namespace {

std::vector<Part> BedParts(const Item& it, Rng& rng) {
  const float hw = it.w / 2, hd = it.d / 2;
  const Color frame = Jitter(kDarkWood, rng), sheet = Jitter({215, 220, 230}, rng, 20);
  return {BoxPart(-hw, -hd, 0, hw, hd - 0.06f, 0.3f, frame),
          BoxPart(-hw + 0.03f, -hd + 0.03f, 0.3f, hw - 0.03f, hd - 0.08f, 0.5f, sheet),
          BoxPart(-hw, hd - 0.06f, 0, hw, hd, 0.95f, frame),  // headboard
          BoxPart(-hw + 0.1f, hd - 0.5f, 0.5f, hw - 0.1f, hd - 0.12f, 0.62f, kWhite)};
}
constexpr ItemSpec kBedDouble{.cls = "bed",
                              .model = "param_bed_double",
                              .mesh_model = "Bed_01",
                              .w = {1.4, 1.8},
                              .d = {2.0, 2.15},
                              .h = 0.95f,
                              .parts = BedParts};
constexpr ItemSpec kBedSingle{.cls = "bed",
                              .model = "param_bed_single",
                              .w = {0.9, 1.0},
                              .d = {2.0, 2.15},
                              .h = 0.95f,
                              .parts = BedParts};

std::vector<Part> NightstandParts(const Item& it, Rng& rng) {
  const Color c = Jitter(kWood, rng);
  std::vector<Part> parts = {
      BoxPart(-0.225f, -0.2f, 0.05f, 0.225f, 0.2f, 0.5f, c),
      BoxPart(-0.225f, -0.2f, 0.5f, 0.225f, 0.2f, 0.52f, Jitter(kDarkWood, rng))};
  for (float x : {-0.2f, 0.18f})
    for (float y : {-0.18f, 0.16f})
      parts.push_back(BoxPart(x, y, 0, x + 0.02f, y + 0.02f, 0.05f, kBlack));
  return parts;
}
constexpr ItemSpec kNightstand{.cls = "nightstand",
                               .model = "param_nightstand",
                               .mesh_model = "NightStand_01",
                               .w = 0.45f,
                               .d = 0.4f,
                               .h = 0.52f,
                               .parts = NightstandParts};

// SmallDecor draws its mesh model.
std::vector<Part> VaseParts(const Item& it, Rng& rng) {
  return {CylPart(0, 0, 0.06f, 0, 0.25f, Jitter({60, 120, 160}, rng, 40))};
}
constexpr ItemSpec kVase{
    .cls = "decor", .model = "param_vase", .w = 0.12f, .d = 0.12f, .h = 0.25f, .parts = VaseParts};

std::vector<Part> WardrobeParts(const Item& it, Rng& rng) {
  const float hw = it.w / 2;
  const Color c = Jitter(rng.Chance(0.5) ? kWhite : kWood, rng);
  std::vector<Part> parts = {BoxPart(-hw, -0.28f, 0.08f, hw, 0.3f, it.h, c),
                             BoxPart(-hw + 0.02f, -0.26f, 0, hw - 0.02f, 0.28f, 0.08f, kDarkWood)};
  for (float x : {-0.06f, 0.04f})
    parts.push_back(BoxPart(x, -0.3f, 0.9f, x + 0.02f, -0.28f, 1.2f, kMetal));
  return parts;
}
constexpr ItemSpec kWardrobe{.cls = "wardrobe",
                             .model = "param_wardrobe",
                             .mesh_model = "Wardrobe_01",
                             .w = {1.0, 1.8},
                             .d = 0.6f,
                             .h = {1.9, 2.2},
                             .parts = WardrobeParts};

// Boards every ~0.5 m of the height, some with a row of books drawn on the way up.
std::vector<Part> ShelfParts(const Item& it, Rng& rng) {
  const float hw = it.w / 2, hd = it.d / 2;
  const Color c = Jitter(rng.Chance(0.5) ? kWood : kWhite, rng);
  std::vector<Part> parts = {BoxPart(-hw, -hd, 0, -hw + 0.025f, hd, it.h, c),
                             BoxPart(hw - 0.025f, -hd, 0, hw, hd, it.h, c),
                             BoxPart(-hw + 0.025f, hd - 0.015f, 0, hw - 0.025f, hd, it.h, c)};
  const int boards = 3 + int(it.h / 0.5f);
  for (int b = 0; b < boards; ++b) {
    const float z = 0.05f + (it.h - 0.07f) * b / (boards - 1);
    parts.push_back(BoxPart(-hw + 0.025f, -hd, z, hw - 0.025f, hd - 0.015f, z + 0.02f, c));
    if (b > 0 && b + 1 < boards && rng.Chance(0.6))  // books
      parts.push_back(BoxPart(
          -hw + 0.05f, -hd + 0.05f, z + 0.02f, -hw + 0.05f + float(rng.Uniform(0.15, it.w - 0.15)),
          hd - 0.05f, z + 0.02f + float(rng.Uniform(0.18, 0.28)), Jitter({140, 60, 50}, rng, 60)));
  }
  return parts;
}
constexpr ItemSpec kShelf{.cls = "shelf",
                          .model = "param_shelf",
                          .w = {0.7, 1.3},
                          .d = 0.35f,
                          .h = {1.4, 2.0},
                          .parts = ShelfParts};

// Chair draws its mesh model.
std::vector<Part> ChairParts(const Item& it, Rng& rng) {
  const Color c = Jitter(kWood, rng);
  std::vector<Part> parts = {BoxPart(-0.22f, -0.23f, 0.42f, 0.22f, 0.21f, 0.46f, c)};
  for (float x : {-0.22f, 0.18f})
    for (float y : {-0.23f, 0.17f})
      parts.push_back(BoxPart(x, y, 0, x + 0.04f, y + 0.04f, 0.42f, c));
  parts.push_back(BoxPart(-0.22f, 0.19f, 0.46f, 0.22f, 0.23f, 0.9f, c));
  return parts;
}
constexpr ItemSpec kChair{
    .cls = "chair", .model = "param_chair", .w = 0.44f, .d = 0.46f, .h = 0.9f, .parts = ChairParts};

// A top on a pedestal (round) or on four legs.
std::vector<Part> TableParts(const Item& it, Rng& rng, bool round) {
  const float w = it.w, d = it.d, h = it.h;
  const Color c = Jitter(rng.Chance(0.5) ? kWood : kWhite, rng);
  std::vector<Part> parts;
  if (round) {
    const float r = std::min(w, d) / 2;
    parts.push_back(CylPart(0, 0, r, h - 0.04f, h, c));
    parts.push_back(CylPart(0, 0, 0.04f, 0.03f, h - 0.04f, kMetal));
    parts.push_back(CylPart(0, 0, std::min(0.25f, r * 0.6f), 0, 0.03f, kMetal));
  } else {
    const float hw = w / 2, hd = d / 2;
    parts.push_back(BoxPart(-hw, -hd, h - 0.04f, hw, hd, h, c));
    for (float x : {-hw + 0.03f, hw - 0.08f})
      for (float y : {-hd + 0.03f, hd - 0.08f})
        parts.push_back(BoxPart(x, y, 0, x + 0.05f, y + 0.05f, h - 0.04f, Jitter(kDarkWood, rng)));
  }
  return parts;
}
std::vector<Part> SquareTableParts(const Item& it, Rng& rng) { return TableParts(it, rng, false); }
std::vector<Part> RoundTableParts(const Item& it, Rng& rng) { return TableParts(it, rng, true); }
// Table takes its size from the caller.
constexpr ItemSpec kTable{.cls = "table", .model = "param_table", .parts = SquareTableParts};
constexpr ItemSpec kRoundTable{
    .cls = "table", .model = "param_table_round", .parts = RoundTableParts};
constexpr ItemSpec kCoffeeTable{.cls = "table",
                                .model = "param_coffee_table",
                                .mesh_model = "CoffeeTable_01",
                                .w = {0.9, 1.2},
                                .d = 0.55f,
                                .h = 0.42f,
                                .parts = SquareTableParts};

std::vector<Part> SofaParts(const Item& it, Rng& rng) {
  const float hw = it.w / 2;
  const Color c = Jitter(kFabric, rng, 40);
  std::vector<Part> parts = {BoxPart(-hw, -0.45f, 0.08f, hw, 0.45f, 0.42f, c),
                             BoxPart(-hw, 0.25f, 0.42f, hw, 0.45f, 0.85f, c),
                             BoxPart(-hw, -0.45f, 0.42f, -hw + 0.15f, 0.25f, 0.62f, c),
                             BoxPart(hw - 0.15f, -0.45f, 0.42f, hw, 0.25f, 0.62f, c)};
  for (float x : {-hw + 0.05f, hw - 0.09f})
    for (float y : {-0.4f, 0.36f})
      parts.push_back(BoxPart(x, y, 0, x + 0.04f, y + 0.04f, 0.08f, kBlack));
  return parts;
}
constexpr ItemSpec kSofa{.cls = "sofa",
                         .model = "param_sofa",
                         .w = {1.8, 2.4},
                         .d = 0.9f,
                         .h = 0.85f,
                         .parts = SofaParts};

std::vector<Part> ArmchairParts(const Item& it, Rng& rng) {
  const Color c = Jitter(kFabric, rng, 50);
  return {BoxPart(-0.425f, -0.425f, 0, 0.425f, 0.425f, 0.42f, c),
          BoxPart(-0.425f, 0.225f, 0.42f, 0.425f, 0.425f, 0.85f, c),
          BoxPart(-0.425f, -0.425f, 0.42f, -0.3f, 0.225f, 0.62f, c),
          BoxPart(0.3f, -0.425f, 0.42f, 0.425f, 0.225f, 0.62f, c)};
}
constexpr ItemSpec kArmchair{.cls = "sofa",
                             .model = "param_armchair",
                             .mesh_model = "SofaB_01",
                             .w = 0.85f,
                             .d = 0.85f,
                             .h = 0.85f,
                             .parts = ArmchairParts};

std::vector<Part> TvStandParts(const Item& it, Rng& rng) {
  return {BoxPart(-it.w / 2, -0.21f, 0.05f, it.w / 2, 0.21f, 0.5f, Jitter(kWhite, rng)),
          BoxPart(-it.w / 2 + 0.05f, -0.19f, 0, it.w / 2 - 0.05f, 0.19f, 0.05f, kBlack)};
}
constexpr ItemSpec kTvStand{.cls = "cabinet",
                            .model = "param_tv_stand",
                            .mesh_model = "TVCabinet_01",
                            .w = {1.4, 1.8},
                            .d = 0.42f,
                            .h = 0.5f,
                            .parts = TvStandParts};

std::vector<Part> TvParts(const Item& it, Rng& rng) {
  return {BoxPart(-0.55f, 0.02f, 0.06f, 0.55f, 0.08f, 0.7f, kBlack),
          BoxPart(-0.15f, -0.1f, 0, 0.15f, 0.1f, 0.02f, kBlack),
          BoxPart(-0.03f, 0.0f, 0.02f, 0.03f, 0.04f, 0.1f, kBlack)};
}
constexpr ItemSpec kTv{.cls = "tv",
                       .model = "param_tv",
                       .mesh_model = "TV_01",
                       .w = 1.1f,
                       .d = 0.2f,
                       .h = 0.7f,
                       .parts = TvParts};

// Base cabinets, worktop and wall cabinets; Counter gives the length.
std::vector<Part> CounterParts(const Item& it, Rng& rng) {
  const float hw = it.w / 2;
  const Color body = Jitter(rng.Chance(0.5) ? kWhite : Color{120, 140, 120}, rng);
  return {BoxPart(-hw, -0.28f, 0.1f, hw, 0.31f, 0.87f, body),
          BoxPart(-hw + 0.02f, -0.25f, 0, hw - 0.02f, 0.31f, 0.1f, kBlack),
          BoxPart(-hw, -0.31f, 0.87f, hw, 0.31f, 0.9f, Jitter({70, 70, 75}, rng)),
          BoxPart(-hw, -0.04f, 1.45f, hw, 0.31f, 2.1f, body)};  // wall cabinets
}
constexpr ItemSpec kCounter{
    .cls = "cabinet", .model = "param_kitchen_counter", .parts = CounterParts};

// The counter's stove where no mesh was drawn (a drawn mesh that does not fit means no stove).
std::vector<Part> CooktopParts(const Item& it, Rng& rng) {
  return {BoxPart(-0.3f, -0.25f, 0, 0.3f, 0.25f, 0.02f, kBlack)};
}
constexpr ItemSpec kCooktop{.cls = "appliance",
                            .model = "param_cooktop",
                            .w = 0.6f,
                            .d = 0.5f,
                            .h = 0.02f,
                            .parts = CooktopParts};

std::vector<Part> FridgeParts(const Item& it, Rng& rng) {
  return {BoxPart(-0.3f, -0.3f, 0.02f, 0.3f, 0.325f, 1.85f, Jitter(kMetal, rng)),
          BoxPart(0.2f, -0.325f, 0.9f, 0.23f, -0.3f, 1.5f, kBlack)};
}
constexpr ItemSpec kFridge{.cls = "appliance",
                           .model = "param_fridge",
                           .mesh_model = "Refrigerator_01",
                           .w = 0.6f,
                           .d = 0.65f,
                           .h = 1.85f,
                           .parts = FridgeParts};

std::vector<Part> BinParts(const Item& it, Rng& rng) {
  return {CylPart(0, 0, 0.15f, 0, 0.4f, Jitter(kMetal, rng, 30))};
}
constexpr ItemSpec kBin{.cls = "bin",
                        .model = "param_bin",
                        .mesh_model = "Trash_01",
                        .w = 0.3f,
                        .d = 0.3f,
                        .h = 0.4f,
                        .parts = BinParts};

// A pot and the foliage, as wide as it is deep: the radius is drawn, not w and d.
ItemSize PlantSize(Rng& rng) {
  const float r = float(rng.Uniform(0.2, 0.3));
  return {2 * r, 2 * r, float(rng.Uniform(0.8, 1.5))};
}
std::vector<Part> PlantParts(const Item& it, Rng& rng) {
  const float r = it.w / 2;  // the drawn radius exactly (w = 2 r)
  return {CylPart(0, 0, 0.14f, 0, 0.3f, Jitter({170, 90, 60}, rng)),
          CylPart(0, 0, r, 0.3f, it.h, Jitter({60, 120, 50}, rng, 25))};
}
constexpr ItemSpec kPlant{
    .cls = "plant", .model = "param_plant", .draw_size = PlantSize, .parts = PlantParts};

std::vector<Part> BathtubParts(const Item& it, Rng& rng) {
  const float hw = it.w / 2;
  return {BoxPart(-hw, -0.375f, 0, hw, 0.375f, 0.1f, kCeramic),
          BoxPart(-hw, -0.375f, 0.1f, hw, -0.305f, 0.55f, kCeramic),
          BoxPart(-hw, 0.305f, 0.1f, hw, 0.375f, 0.55f, kCeramic),
          BoxPart(-hw, -0.305f, 0.1f, -hw + 0.07f, 0.305f, 0.55f, kCeramic),
          BoxPart(hw - 0.07f, -0.305f, 0.1f, hw, 0.305f, 0.55f, kCeramic)};
}
constexpr ItemSpec kBathtub{.cls = "bathtub",
                            .model = "param_bathtub",
                            .w = {1.5, 1.75},
                            .d = 0.75f,
                            .h = 0.55f,
                            .parts = BathtubParts};

std::vector<Part> ToiletParts(const Item& it, Rng& rng) {
  return {BoxPart(-0.2f, 0.16f, 0.35f, 0.2f, 0.34f, 0.8f, kCeramic),
          CylPart(0, -0.06f, 0.19f, 0, 0.42f, kCeramic),
          BoxPart(-0.12f, -0.06f, 0, 0.12f, 0.16f, 0.4f, kCeramic)};
}
constexpr ItemSpec kToilet{.cls = "toilet",
                           .model = "param_toilet",
                           .w = 0.4f,
                           .d = 0.68f,
                           .h = 0.8f,
                           .parts = ToiletParts};

std::vector<Part> SinkParts(const Item& it, Rng& rng) {
  const float hw = it.w / 2;
  return {BoxPart(-hw, -0.23f, 0, hw, 0.23f, 0.8f, Jitter(kWhite, rng)),
          BoxPart(-hw, -0.23f, 0.8f, hw, 0.23f, 0.88f, kCeramic)};
}
constexpr ItemSpec kSink{.cls = "sink",
                         .model = "param_sink",
                         .w = {0.5, 0.8},
                         .d = 0.46f,
                         .h = 0.88f,
                         .parts = SinkParts};

std::vector<Part> ConsoleParts(const Item& it, Rng& rng) {
  return {BoxPart(-it.w / 2, -0.16f, 0, it.w / 2, 0.16f, 0.9f, Jitter(kWood, rng))};
}
constexpr ItemSpec kShoeRack{.cls = "cabinet",
                             .model = "param_console",
                             .mesh_model = "ShoeRack_01",
                             .w = {0.8, 1.1},
                             .d = 0.32f,
                             .h = 0.9f,
                             .parts = ConsoleParts};

std::vector<Part> SideboardParts(const Item& it, Rng& rng) {
  return {BoxPart(-it.w / 2, -0.225f, 0.1f, it.w / 2, 0.225f, 0.85f, Jitter(kWood, rng)),
          BoxPart(-it.w / 2 + 0.03f, -0.2f, 0, it.w / 2 - 0.03f, 0.2f, 0.1f, kBlack)};
}
constexpr ItemSpec kSideboard{.cls = "cabinet",
                              .model = "param_sideboard",
                              .w = {1.2, 1.8},
                              .d = 0.45f,
                              .h = 0.85f,
                              .parts = SideboardParts};

// Portrait draws its mesh model.
std::vector<Part> PictureParts(const Item& it, Rng& rng) {
  return {BoxPart(-it.w / 2, -0.015f, 0, it.w / 2, 0.015f, it.h, Jitter({120, 100, 140}, rng, 60))};
}
constexpr ItemSpec kPicture{.cls = "decor",
                            .model = "param_picture",
                            .w = {0.4, 0.9},
                            .d = 0.03f,
                            .h = {0.3, 0.6},
                            .parts = PictureParts};

// Rug gives the size.
std::vector<Part> RugParts(const Item& it, Rng& rng) {
  return {BoxPart(-it.w / 2, -it.d / 2, 0.002f, it.w / 2, it.d / 2, 0.012f,
                  Jitter({150, 60, 60}, rng, 60))};
}
constexpr ItemSpec kRug{.cls = "carpet", .model = "param_rug", .walkable = true, .parts = RugParts};

// The spec's size: drawn by draw_size, else w, d and h in that order.
ItemSize DrawSize(const ItemSpec& spec, Rng& rng) {
  if (spec.draw_size) return spec.draw_size(rng);
  return {spec.w.Draw(rng), spec.d.Draw(rng), spec.h.Draw(rng)};
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The builders.

Item Furnisher::Build(const ItemSpec& spec) {
  if (spec.mesh_model) return Build(spec, spec.mesh_model);
  return Parametric(spec, DrawSize(spec, rng));
}

Item Furnisher::Build(const ItemSpec& spec, const std::string& mesh_model) {
  if (const PreparedMesh* m = cat.Mesh(mesh_model))
    return Catalogue::MeshItem(spec.cls, mesh_model, m);
  return Parametric(spec, DrawSize(spec, rng));
}

Item Furnisher::Parametric(const ItemSpec& spec, const ItemSize& size) {
  Item it;
  it.cls = spec.cls;
  it.model = spec.model;
  it.w = size.w;
  it.d = size.d;
  it.h = size.h;
  it.walkable = spec.walkable;
  it.parts = spec.parts(it, rng);
  return it;
}

Item Furnisher::Bed(bool dbl) { return Build(dbl ? kBedDouble : kBedSingle); }

Item Furnisher::Nightstand() { return Build(kNightstand); }

Item Furnisher::SmallDecor() {
  static const char* kModels[] = {"Vase_01", "DeskPortraitA_01", "DeskPortraitB_01"};
  const std::string model = kModels[rng.Int(0, 2)];
  return Build(kVase, model);
}

Item Furnisher::Wardrobe() { return Build(kWardrobe); }

Item Furnisher::Shelf() { return Build(kShelf); }

Item Furnisher::Chair() {
  static const char* kModels[] = {"ChairA_01", "ChairD_01"};
  const std::string model = kModels[rng.Int(0, 1)];
  return Build(kChair, model);
}

Item Furnisher::Table(float w, float d, float h, bool round) {
  return Parametric(round ? kRoundTable : kTable, {w, d, h});
}

Item Furnisher::Desk() {
  if (const PreparedMesh* m = cat.Mesh("ReadingDesk_01"))
    return Catalogue::MeshItem("desk", "ReadingDesk_01", m);
  // Not a spec: the two draws are arguments of one call, and which runs first is the compiler's
  // choice; a spec would fix an order, maybe another one.
  Item it = Table(float(rng.Uniform(1.1, 1.5)), float(rng.Uniform(0.6, 0.7)), 0.75f, false);
  it.cls = "desk";
  it.model = "param_desk";
  return it;
}

// A desk with its chair in front (the chair faces the desk).
Item Furnisher::DeskGroup() {
  Item desk = Desk(), chair = Chair();
  Item g;
  g.w = std::max(desk.w, chair.w);
  g.d = desk.d + 0.1f + chair.d;
  g.children.push_back({desk, 0, g.d / 2 - desk.d / 2, 0, 0});
  g.children.push_back({chair, 0, -g.d / 2 + chair.d / 2, 0, 2});
  return g;
}

Item Furnisher::DiningGroup(int chairs_per_side) {
  Item table;
  if (const PreparedMesh* m = cat.Mesh("KitchenTable_01")) {
    table = Catalogue::MeshItem("table", "KitchenTable_01", m);
  } else {
    const bool round = chairs_per_side == 1 && rng.Chance(0.4);
    const float w =
        round ? 0.9f : float(chairs_per_side == 1 ? rng.Uniform(0.8, 1.0) : rng.Uniform(1.4, 1.8));
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

Item Furnisher::Sofa() { return Build(kSofa); }

Item Furnisher::Armchair() { return Build(kArmchair); }

Item Furnisher::CoffeeTable() { return Build(kCoffeeTable); }

// Sofa with a coffee table in front of it.
Item Furnisher::SofaGroup() {
  Item sofa = Sofa(), table = CoffeeTable();
  if (table.w > sofa.w) return sofa;
  Item g;
  g.w = sofa.w;
  g.d = sofa.d + 0.4f + table.d;
  g.children.push_back({sofa, 0, g.d / 2 - sofa.d / 2, 0, 0});
  g.children.push_back({table, 0, -g.d / 2 + table.d / 2, 0, 0});
  return g;
}

Item Furnisher::TvGroup() {
  Item stand = Build(kTvStand);
  Item tv = Build(kTv);
  if (tv.w > stand.w || tv.d > stand.d) return stand;
  stand.children.push_back({tv, 0, stand.d / 2 - tv.d / 2 - 0.02f, stand.h, 0});
  return stand;
}

Item Furnisher::Counter(float length) {
  Item it = Parametric(kCounter, {length, 0.62f, 2.1f});
  const float hw = length / 2;
  if (const PreparedMesh* m = cat.Mesh("CookingBench_01")) {
    Item stove = Catalogue::MeshItem("appliance", "CookingBench_01", m);
    if (stove.w < length - 0.1f && stove.d < it.d)
      it.children.push_back({stove, -hw + stove.w / 2 + 0.05f, 0, 0.9f, 0});
  } else {
    Item stove = Build(kCooktop);
    if (length > 0.8f) it.children.push_back({stove, -hw + 0.4f, -0.02f, 0.9f, 0});
  }
  return it;
}

Item Furnisher::Fridge() { return Build(kFridge); }

Item Furnisher::Bin() { return Build(kBin); }

Item Furnisher::Plant() { return Build(kPlant); }

Item Furnisher::Bathtub() { return Build(kBathtub); }

Item Furnisher::Toilet() { return Build(kToilet); }

Item Furnisher::Sink() { return Build(kSink); }

Item Furnisher::ShoeRack() { return Build(kShoeRack); }

Item Furnisher::SideCabinet() { return Build(kSideboard); }

// A picture on the wall, 1.2-1.5 m up; a group so the footprint is the picture's.
Item Furnisher::Portrait() {
  static const char* kModels[] = {"PortraitA_01", "PortraitB_01", "PortraitD_01", "PortraitE_01"};
  const std::string model = kModels[rng.Int(0, 3)];
  Item pic = Build(kPicture, model);
  Item g;
  g.w = pic.w;
  g.d = pic.d;
  g.children.push_back({pic, 0, 0, float(rng.Uniform(1.2, 1.5)), 0});
  return g;
}

Item Furnisher::Rug(float max_w, float max_d) {
  const float w = std::min(max_w, float(rng.Uniform(1.4, 2.4)));
  const float d = std::min(max_d, float(rng.Uniform(1.0, 1.8)));
  return Parametric(kRug, {w, d, 0.012f});
}

}  // namespace voxplan::apartment
