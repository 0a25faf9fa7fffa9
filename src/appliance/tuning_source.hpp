#pragma once
// Where `epa simulate` and `epa design` get their model and controller polynomials from: the
// paper by default, a model file (--model, epa-model/1) and a design file (--design, epa-design/1).
#include <string>

#include "core/model_file.hpp"
#include "core/polynomial.hpp"
#include "core/result.hpp"

namespace epa::appliance {

struct ControllerPolynomials {
  core::Polynomial F, G, H;
  std::string source;  // "paper eq 12-13" or the design file's path
};

// The paper's model (eq 9-10) when path is empty, else the model file.
core::Result<core::ModelFile> load_model(const std::string& path);

// The paper's F, G (eq 12-13, H = G) when path is empty, else F, G, H of an epa-design/1 file.
core::Result<ControllerPolynomials> load_controller_polynomials(const std::string& design_json_path);

}  // namespace epa::appliance
