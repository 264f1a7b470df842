#pragma once
// The headers nearly every test includes, precompiled once for all of them (tests/CMakeLists.txt: ff_test_pch). Only
// third-party and standard headers: a change to our own code must not rebuild the precompiled header. A test still
// includes what it uses itself (this file is a compile-time cache, not an include); since every test sees these
// headers anyway, a missing include shows only in a build configured with -DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <fmt/format.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>
