// One executed action of the intrinsic phase, as the eye reported it
// (Algorithm 1 lines 1-6): what the predictors learn from, and what their
// memory keeps (memory.hpp).
#pragma once
#include <cstdint>
#include <vector>

#include "predictors/perceptron.hpp"

namespace afford {

struct Experience {
  int action = 0;
  std::vector<std::uint8_t> before_image;  // focus image of the scan (object_image)
  double before_x = 0, before_y = 0;       // object_position
  double target_x = -1, target_y = -1;     // move target (where-effect input)
  bool affordance = false;                 // the action's effect was seen
  std::vector<std::uint8_t> after_image;   // new_object_image
  double after_x = 0, after_y = 0;         // new_object_position
  // before_image as the perceptrons take it (focusInput), when the memory keeps
  // the experience: replay does not convert it again. Empty: not made yet.
  SparseInput before_input;
};

// e.before_input, or the conversion of e.before_image when it was not kept.
inline SparseInput inputOf(const Experience& e) {
  return e.before_input.index.empty() ? focusInput(e.before_image) : e.before_input;
}

}  // namespace afford
