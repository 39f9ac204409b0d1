// bake_plan: the texture half of the method, the output model, the bake (§4.3) and the metrics.
#include "core/error.hpp"
#include "core/progress.hpp"
#include "core/resources.hpp"
#include "pipeline/bake_material_maps.hpp"
#include "pipeline/output_model.hpp"
#include "pipeline/plan_state.hpp"
#include "pipeline/stage_clock.hpp"
#include "report/metrics.hpp"

namespace tightex {

namespace {

/// Bakes the new textures of `om` from the input (§4.3, Alg. 3, then the least-squares fit).
BakeStats bake_new_textures(const TexturedMesh& input, const Options& options, const StageProgress& progress, OutputModel& om) {
  std::vector<Image> images;
  for (int i = 0; i < om.new_images; ++i) images.push_back(std::move(om.mesh.textures[size_t(i)].image));
  BakeStats bs;
  BakeOptions bo;
  bo.fit = options.fit;
  if (options.fine_fit) bo.fit_samples = kFineFitSamples, bo.fit_lambda = kFineFitLambda;
  bo.progress = progress.of_stage("bake");
  bake_texture(input, om.bake_triangles, om.rects, images, &bs, bo);
  for (size_t i = 0; i < images.size(); ++i) om.mesh.textures[i].image = std::move(images[i]);
  return bs;
}

/// Frees what only the output model needed of `plan`: each mapped component's surface, disk and
/// texture coordinates (a kept component's surface stays: Plan::kept_triangles counts it).
void release_maps(Plan::State& plan) {
  for (size_t c = 0; c < plan.components.size(); ++c) {
    if (c < plan.kept.size() && !plan.kept[c].empty()) continue;
    plan.components[c] = Surface{};
    if (c < plan.disks.size()) plan.disks[c] = Disk{};
    if (c < plan.uv.size()) plan.uv[c] = std::vector<Vec2>{};
  }
  plan.maps_released = true;
}

/// bake_plan's work on `state`, whose maps are released (release_maps) once the output model holds
/// them where `release` is set.
Result bake_state(const Plan::State& state, const TexturedMesh& input, const Options& options, Plan::State* release) {
  if (state.maps_released) fail_input("the plan was baked already, and its maps freed (bake_plan_releasing_maps)");
  if (input_fingerprint(input) != state.input_fingerprint)
    fail_input("{}: not the mesh the plan was made from ({} triangles, {} vertices): bake_plan needs the planned mesh",
               input.source.empty() ? std::string("mesh") : input.source, input.num_triangles(), input.num_vertices());
  const StageProgress progress(options.progress);
  ReportData rep = state.report;
  StageClock clock(rep.timings);
  // 5. The output model: the input's positions and triangles, new texture coordinates; components the
  //    plan could not map keep their input texture coordinates and materials.
  OutputModel om = build_output_model(state, input);
  if (release) {
    release_maps(*release);
    release_free_memory();  // the maps' memory, for the bake's arrays
  }
  // 6. Bake the new textures (§4.3).
  progress("bake", 0);
  rep.bake = bake_new_textures(input, options, progress, om);
  clock.done("bake");
  // 6b. Every other map the materials bind, through the same layout.
  rep.maps = bake_material_maps(input, options, om);
  if (!rep.maps.empty()) clock.done("bake_maps");
  Result result;
  result.output = std::move(om.mesh);
  // 7. Measure (docs/metrics.md).
  if (options.measure) {
    progress("measure", 0);
    rep.metrics = measure(input, result.output);
    clock.done("measure");
  }
  rep.peak_rss_mib = peak_rss_mib();
  result.report = public_report(to_json(rep), result.output, size_t(om.new_images));
  progress("done", 1);
  return result;
}

}  // namespace

Plan::Plan() = default;
Plan::Plan(std::unique_ptr<State> state) : state_(std::move(state)) {}
Plan::Plan(Plan&&) noexcept = default;
Plan& Plan::operator=(Plan&&) noexcept = default;
Plan::~Plan() = default;

const Plan::State& plan_state(const Plan& plan) {
  if (!plan.state_) fail_input("the plan is empty (made by plan_charts?)");
  return *plan.state_;
}

Plan::State& mutable_plan_state(Plan& plan) {
  if (!plan.state_) fail_input("the plan is empty (made by plan_charts?)");
  return *plan.state_;
}

Report Plan::report() const { return public_report(plan_state(*this).report_json); }

std::vector<std::pair<int, int>> Plan::texture_sizes() const { return plan_state(*this).image_size; }

size_t Plan::kept_components() const {
  size_t n = 0;
  for (const std::string& k : plan_state(*this).kept) n += !k.empty();
  return n;
}

size_t Plan::kept_triangles() const {
  size_t n = 0;
  for (size_t c = 0; c < plan_state(*this).kept.size(); ++c)
    if (!plan_state(*this).kept[c].empty()) n += plan_state(*this).components[c].num_faces();
  return n;
}

std::string Plan::first_kept_reason() const {
  for (const std::string& k : plan_state(*this).kept)
    if (!k.empty()) return k;
  return {};
}

Result bake_plan(const Plan& plan, const TexturedMesh& input, const Options& options) {
  return bake_state(plan_state(plan), input, options, nullptr);
}

Result bake_plan_releasing_maps(Plan& plan, const TexturedMesh& input, const Options& options) {
  Plan::State& state = mutable_plan_state(plan);
  return bake_state(state, input, options, &state);
}

}  // namespace tightex
