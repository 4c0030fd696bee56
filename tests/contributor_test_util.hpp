// A declared contributor built in a test: the catalog's entry `id` with one u for every axis.
#pragma once
#include <gtest/gtest.h>

#include <Eigen/Core>

#include "core/contributors.hpp"

namespace rotacal::test {

inline Contributor contributorItem(const char* id, double u_internal) {
  Contributor c;
  c.info = findContributor(id);
  EXPECT_NE(c.info, nullptr) << id;
  c.u = Eigen::Vector3d::Constant(u_internal);
  return c;
}

}  // namespace rotacal::test
