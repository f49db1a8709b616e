#pragma once
// flexbody/runtime/scene_body.hpp: how a scene takes a body from a body file, with the names of fbsim's scene keys
// (docs/scenes.md): which modes (all, the first k, rigid, or the unreduced mesh), the formulation (improved GCMS or
// FFRF) and its frame, damping and the geometric stiffness. SceneBuilder::add_body(name, SceneBody) reads the file
// and makes the model; its refusals are SceneErrors that name the key at fault, so that a scene file can point at
// its line.

#include "flexbody/format/body_file.hpp"
#include "flexbody/runtime/body_model.hpp"
#include "flexbody/runtime/ffrf_model.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

namespace flexbody::runtime {

/// A body's damping (damping.hpp): modal ratios ζ [1] and Rayleigh's D = α M + β K (α [1/s], β [s]), summed.
struct BodyDamping {
  std::optional<double> modal;                  ///< ζ of every mode
  std::optional<Eigen::VectorXd> modal_ratios;  ///< ζ_1 … ζ_n, one per mode (instead of `modal`)
  std::optional<double> alpha;                  ///< α [1/s]; none: 0
  std::optional<double> beta;                   ///< β [s]; none: 0
};

struct SceneBody {
  std::filesystem::path file;  ///< the body file (*.fbh5)
  /// modes: none = all the file holds, 0 = rigid, k = the first k.
  std::optional<Eigen::Index> modes;
  /// The unreduced improved ACF of the file's mesh (fbsim's `modes: full`, the reference); `modes` must be none.
  bool full = false;
  enum class Formulation {
    automatic,  ///< the improved GCMS for an elastic body; a rigid one moves in 7 floating-frame coordinates
    gcms,       ///< the improved GCMS (a rigid body: its 12 coordinates τ, A with 6 orthogonality rows)
    ffrf        ///< the floating frame of reference formulation with the same modes
  };
  Formulation formulation = Formulation::automatic;
  /// formulation ffrf only: the floating frame, mean-axis (none) or an interface's (its name).
  std::optional<FloatingFrame> frame;
  std::string frame_interface;  ///< FloatingFrame::interface: which
  std::optional<BodyDamping> damping;
  /// The body file's geometric stiffness (fbprep --geometric-stiffness): none = used when the file holds it, true =
  /// required, false = left out.
  std::optional<bool> geometric_stiffness;
  /// Keep the output regions' stress modes (most of a body file's size); a scene that recovers no stress of this
  /// body saves the memory.
  bool stresses = true;
};

/// A refusal of a scene's item; `key()` names the item's key at fault ("file", "modes", "formulation", "frame",
/// "damping", "geometric_stiffness"), what() says why in one line.
class SceneError : public std::invalid_argument {
 public:
  SceneError(std::string key, const std::string& message) : std::invalid_argument(message), key_(std::move(key)) {}
  [[nodiscard]] const std::string& key() const { return key_; }

 private:
  std::string key_;
};

/// The model of body `name` that `spec` asks for, from `data` (read from spec.file). Throws SceneError: the body
/// model's own message for a count of modes the file does not hold (key "modes"), else one naming "body 'name'".
[[nodiscard]] BodyModel make_body_model(const std::string& name, const SceneBody& spec, const format::BodyData& data);

}  // namespace flexbody::runtime
