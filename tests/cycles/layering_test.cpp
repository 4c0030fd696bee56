// The shape of the tree, checked so that it cannot regress: outside cycles/<name>/ and the
// registry no source file names a cycle, outside controllers/<name>/ and the dialects' registry no
// string names a dialect, no product file includes a dialect's folder but that folder, and each
// layer imports only the layers below it.
#include <gtest/gtest.h>

#include <filesystem>
#include <algorithm>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "controllers/dialect.hpp"
#include "cycles/cycle.hpp"

namespace rotacal {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Product source files of a layer (tests and examples may name cycles: they exercise them).
std::vector<fs::path> sources(const std::string& layer) {
  std::vector<fs::path> out;
  const fs::path root = fs::path(ROTACAL_SOURCE_DIR) / layer;
  if (!fs::exists(root)) return out;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    const auto ext = e.path().extension();
    if (e.is_regular_file() && (ext == ".cpp" || ext == ".hpp" || e.path().filename() == "CMakeLists.txt"))
      out.push_back(e.path());
  }
  return out;
}

std::vector<std::string> everyCycleName() {
  std::vector<std::string> names;
  for (const Cycle* c : cycles()) {
    names.emplace_back(c->name());
    for (const auto& a : c->aliases()) names.push_back(a);
  }
  return names;
}

// Every place a name occurs as a word, "FILE:LINE: text".
std::vector<std::string> mentions(const fs::path& file, const std::string& name) {
  std::vector<std::string> out;
  const std::regex word("(^|[^A-Za-z0-9_])" + name + "([^A-Za-z0-9_]|$)");
  std::istringstream in(slurp(file));
  std::string line;
  for (int n = 1; std::getline(in, line); ++n)
    if (std::regex_search(line, word)) out.push_back(file.string() + ":" + std::to_string(n) + ": " + line);
  return out;
}

TEST(Layering, RegistryListsFiveCyclesWithDistinctNames) {
  const auto names = everyCycleName();
  ASSERT_GE(cycles().size(), 5u);
  for (size_t i = 0; i < names.size(); ++i)
    for (size_t j = i + 1; j < names.size(); ++j) EXPECT_NE(names[i], names[j]);
  for (const Cycle* c : cycles()) {
    EXPECT_EQ(&cycleByName(c->name()), c);
    ProbePlan p;
    for (const auto& a : c->aliases()) {
      p.cycle = a;
      EXPECT_EQ(&cycleOfPlan(p), c) << a;
    }
  }
  EXPECT_THROW(cycleByName("no_such_cycle"), std::invalid_argument);
}

TEST(Layering, NoCycleIsNamedOutsideItsFolderAndTheRegistry) {
  std::vector<std::string> found;
  for (const std::string layer : {"core", "gcode", "controllers", "postproc", "report", "history", "cli"})
    for (const auto& f : sources(layer))
      for (const auto& n : everyCycleName())
        for (const auto& m : mentions(f, n)) found.push_back(m);
  // Inside cycles/: only a cycle's own folder and registry.cpp name it... and the shared
  // files of cycles/ (probing.cpp, cycle.hpp) none.
  for (const auto& f : sources("cycles")) {
    const fs::path rel = fs::relative(f, fs::path(ROTACAL_SOURCE_DIR) / "cycles");
    if (rel == "registry.cpp") continue;
    const std::string folder = rel.has_parent_path() ? rel.begin()->string() : "";
    if (!folder.empty()) continue;  // a cycle's folder may name itself and, in prose, another cycle
    for (const auto& n : everyCycleName())
      for (const auto& m : mentions(f, n)) found.push_back(m);
  }
  std::string all;
  for (const auto& m : found) all += m + "\n";
  EXPECT_TRUE(found.empty()) << found.size() << " mentions of a cycle outside cycles/<name>/:\n" << all;
}

// Every string literal that is exactly `name` ("FILE:LINE: text"): code that asks for a dialect by
// name instead of asking the dialect (its DialectIdentity).
std::vector<std::string> literals(const fs::path& file, const std::string& name) {
  std::vector<std::string> out;
  const std::string quoted = "\"" + name + "\"";
  std::istringstream in(slurp(file));
  std::string line;
  for (int n = 1; std::getline(in, line); ++n)
    if (line.find(quoted) != std::string::npos) out.push_back(file.string() + ":" + std::to_string(n) + ": " + line);
  return out;
}

TEST(Layering, RegistryListsEveryDialectOnceByItsName) {
  const auto names = dialectNames();
  ASSERT_EQ(names.size(), dialects().size());
  for (size_t i = 0; i < names.size(); ++i) {
    EXPECT_EQ(&dialectByName(names[i]), dialects()[i]);
    EXPECT_TRUE(fs::is_directory(fs::path(ROTACAL_SOURCE_DIR) / "controllers" / names[i])) << names[i];
    for (size_t j = i + 1; j < names.size(); ++j) EXPECT_NE(names[i], names[j]);
  }
  EXPECT_EQ(findDialect("no_such_dialect"), nullptr);
  EXPECT_THROW(dialectByName("no_such_dialect"), std::invalid_argument);
}

TEST(Layering, NoDialectIsNamedOutsideItsFolderAndTheRegistry) {
  const fs::path controllers = fs::path(ROTACAL_SOURCE_DIR) / "controllers";
  std::vector<std::string> found;
  for (const std::string layer : {"core", "gcode", "controllers", "postproc", "cycles", "tasks", "report", "history",
                                  "api", "include", "cli"})
    for (const auto& f : sources(layer)) {
      const fs::path rel = fs::relative(f, controllers);
      if (rel == "registry.cpp") continue;
      // A dialect's folder names itself (its results header, its messages), and only itself.
      const std::string own = layer == "controllers" && rel.has_parent_path() ? rel.begin()->string() : "";
      for (const auto& n : dialectNames())
        if (n != own)
          for (const auto& m : literals(f, n)) found.push_back(m);
    }
  std::string all;
  for (const auto& m : found) all += m + "\n";
  EXPECT_TRUE(found.empty()) << found.size() << " string literals naming a dialect outside controllers/<name>/ (ask the "
                             << "dialect's identity instead, controllers/dialect.hpp):\n"
                             << all;
}

// The dialect folders a file includes from: "okuma" for `#include "controllers/okuma/..."`.
std::vector<std::string> includedDialectFolders(const fs::path& file) {
  std::vector<std::string> out;
  const std::regex inc(R"(^\s*#\s*include\s+"controllers/([A-Za-z0-9_]+)/)");
  std::istringstream in(slurp(file));
  std::string line;
  std::smatch m;
  while (std::getline(in, line))
    if (std::regex_search(line, m, inc)) out.push_back(m.str(1));
  return out;
}

// What a dialect's folder holds is its own: another dialect that needs it would make the two one
// dialect in two folders, and what the dialects share belongs in a file of controllers/ itself,
// which (like every other product layer) asks the registry and includes no dialect's folder.
TEST(Layering, NoDialectFolderIsIncludedFromOutsideIt) {
  const fs::path controllers = fs::path(ROTACAL_SOURCE_DIR) / "controllers";
  std::vector<std::string> found;
  for (const std::string layer : {"core", "gcode", "controllers", "postproc", "cycles", "tasks", "report", "history",
                                  "api", "include", "cli"})
    for (const auto& f : sources(layer)) {
      const fs::path rel = fs::relative(f, controllers);
      const std::string own = layer == "controllers" && rel.has_parent_path() ? rel.begin()->string() : "";
      for (const auto& folder : includedDialectFolders(f))
        if (folder != own) found.push_back(f.string() + " includes controllers/" + folder + "/");
    }
  std::string all;
  for (const auto& m : found) all += m + "\n";
  EXPECT_TRUE(found.empty()) << found.size() << " includes of a dialect's folder from outside it (move what is shared "
                             << "into a file of controllers/):\n"
                             << all;
}

// `#include "layer/..."` lines of a file.
std::vector<std::string> includedLayers(const fs::path& file) {
  std::vector<std::string> out;
  const std::regex inc(R"(^\s*#\s*include\s+"([a-z_]+)/)");
  std::istringstream in(slurp(file));
  std::string line;
  std::smatch m;
  while (std::getline(in, line))
    if (std::regex_search(line, m, inc)) out.push_back(m.str(1));
  return out;
}

TEST(Layering, EachLayerImportsOnlyTheLayersBelowIt) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> forbidden = {
      {"core", {"cycles", "controllers", "postproc", "cli", "report", "history", "gcode"}},
      {"gcode", {"cycles", "controllers", "postproc", "cli"}},
      {"cycles", {"controllers", "cli"}},
      {"controllers", {"cycles", "cli"}},
      {"postproc", {"cycles", "cli"}},
      {"report", {"cycles", "controllers", "cli"}},
      {"history", {"cycles", "controllers", "cli"}},
  };
  std::vector<std::string> found;
  for (const auto& [layer, bad] : forbidden)
    for (const auto& f : sources(layer))
      for (const auto& inc : includedLayers(f))
        for (const auto& b : bad)
          if (inc == b) found.push_back(f.string() + " includes " + b + "/");
  std::string all;
  for (const auto& m : found) all += m + "\n";
  EXPECT_TRUE(found.empty()) << all;
}

}  // namespace
}  // namespace rotacal
