#include "flexbody/runtime/scene_body.hpp"

#include "flexbody/runtime/damping.hpp"
#include "flexbody/runtime/full_order.hpp"

#include <memory>

namespace flexbody::runtime {
namespace {

// A refusal for `key` (no fmt here: the runtime's messages are plain strings).
[[noreturn]] void refuse(const char* key, const std::string& message) { throw SceneError(key, message); }

// Stiffness-proportional damping only (D̂ = β K̄ keeps the full-order body's Newton core sparse, full_order.hpp).
bool stiffness_proportional(const BodyDamping& d) {
  return !d.modal && !d.modal_ratios && (!d.alpha || *d.alpha == 0.0) && d.beta.has_value();
}

void add_damping(BodyModel& model, const BodyDamping& d, const std::string& where) {
  std::optional<Eigen::VectorXd> ratios = d.modal_ratios;
  if (d.modal && d.modal_ratios)
    refuse("damping", where + " damping: give modal (every mode's ratio) or modal_ratios, not both");
  if (ratios && ratios->size() != model.modes)
    refuse("damping", where + " damping modal lists " + std::to_string(ratios->size()) + " ratios for " +
                          std::to_string(model.modes) + " modes");
  if (d.modal) ratios = Eigen::VectorXd::Constant(model.modes, *d.modal);
  try {
    model.damping = rayleigh_damping(model, d.alpha.value_or(0.0), d.beta.value_or(0.0));
    if (ratios) model.damping += modal_damping(model, *ratios);
  } catch (const std::invalid_argument& e) {  // a ratio outside [0, 1], a negative alpha or beta
    refuse("damping", where + " damping: " + e.what());
  }
}

}  // namespace

BodyModel make_body_model(const std::string& name, const SceneBody& spec, const format::BodyData& data) {
  const std::string where = "body '" + name + "'";
  const std::string file = spec.file.filename().string();
  if (spec.full && spec.modes)
    refuse("modes", where + " modes: full is the unreduced mesh and takes no count of modes");
  BodyModel model;
  try {
    model = spec.full ? full_order_model(data, file) : make_body_model(data, spec.modes, file, spec.stresses);
  } catch (const std::invalid_argument& e) {
    refuse("modes", e.what());
  }
  if (!spec.stresses) model.recovery.clear();
  if (spec.geometric_stiffness) {
    if (!*spec.geometric_stiffness)
      model.prestress.reset();
    else if (spec.full)
      refuse("geometric_stiffness", where +
                                        " geometric_stiffness: the body file stores it projected on the modes, so "
                                        "modes: full (the unreduced model) has none");
    else if (model.rigid())
      refuse("geometric_stiffness", where + " geometric_stiffness: a rigid body has no deformation to stiffen");
    else if (!model.prestress)
      refuse("geometric_stiffness", where + " geometric_stiffness: " + file +
                                        " holds none (fbprep --geometric-stiffness, or geometric_stiffness: true in "
                                        "its body spec, writes it)");
  }
  const bool ffrf = spec.formulation == SceneBody::Formulation::ffrf;
  if (spec.full && ffrf)
    refuse("formulation", where +
                              ": formulation ffrf moves modes in a floating frame; modes: full is the unreduced "
                              "improved ACF (use a number of modes, or formulation gcms)");
  if (spec.full && spec.damping) {
    if (!stiffness_proportional(*spec.damping))
      refuse("damping", where +
                            " damping: modes: full takes stiffness-proportional damping only, {rayleigh: {beta: β}} "
                            "(β in s), which keeps its Newton matrix sparse");
    try {
      model = damp_full_order(std::move(model), *spec.damping->beta);
    } catch (const std::invalid_argument& e) {
      refuse("damping", where + " damping: " + e.what());
    }
  } else if (spec.damping) {
    add_damping(model, *spec.damping, where);
  }
  if (spec.frame && !ffrf)
    refuse("frame",
           where + ": frame belongs to formulation ffrf (the improved GCMS's frame is always the mean-axis one)");
  const bool floating =
      ffrf || (spec.modes && *spec.modes == 0 && spec.formulation == SceneBody::Formulation::automatic);
  if (floating) {
    const FloatingFrame kind = spec.frame.value_or(FloatingFrame::mean_axis);
    try {
      model.floating_frame = std::make_shared<const FfrfModel>(
          make_ffrf_model(model, kind, kind == FloatingFrame::interface ? spec.frame_interface : std::string()));
    } catch (const std::invalid_argument& e) {
      if (spec.frame) refuse("frame", where + " frame: " + e.what());
      refuse("formulation", where + " formulation: " + e.what());
    }
  }
  return model;
}

}  // namespace flexbody::runtime
