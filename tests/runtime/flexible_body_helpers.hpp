#pragma once
// What flexible_body_test.cpp and flexible_body_reference_test.cpp share: steel and the small beam's body data.
#include "flexbody/format/body_file.hpp"
#include "flexbody/preprocess/material.hpp"
#include "test_bodies.hpp"
#include "test_meshes.hpp"

namespace flexible_body {

namespace fp = flexbody::preprocess;

inline const fp::Material kSteel{"steel", 210e9, 0.3, 7850.0};

// A 0.5 x 0.05 x 0.05 m steel beam (10 x 2 x 2 cells), 4 free-free modes, as a body file would hold it.
inline const flexbody::format::BodyData& beam() {
  static const flexbody::format::BodyData body = [] {
    return flexbody::test::free_free_body(flexbody::test::assemble(flexbody::test::box_mesh(0.5, 0.05, 0.05, 10, 2, 2), kSteel),
                                          kSteel, 4);
  }();
  return body;
}

}  // namespace flexible_body
