// The unsafe-program corpus (tests/data/unsafe/MANIFEST.tsv): programs rotacal writes, each edited
// the way a hand, a bad transfer or a careless post-processor edits them, each unsafe on the
// machine, each refused by `rotacal check` at the line of the edit it names. The base programs are
// generated here by the built binary, so the corpus follows the generator; an edit whose text is
// no longer in the base fails loudly (the manifest is then brought up to date, never dropped).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "dialect_lists.hpp"

namespace rotacal {
namespace {

namespace fs = std::filesystem;
using test::sh;
using test::slurp;

const std::string kMachine = std::string(ROTACAL_SOURCE_DIR) + "/examples/machines/ac_trunnion.json";
const std::string kManifest = std::string(ROTACAL_SOURCE_DIR) + "/tests/data/unsafe/MANIFEST.tsv";
const std::vector<std::string> kDialects = test::programDialects();

struct Case {
  int manifest_line = 0;
  std::string name, dialect, cycle, kind, op, find, text, line, message;
};

// \n and \t in a manifest field are a newline and a tab, \\ a backslash.
std::string unescape(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\\' && i + 1 < s.size()) {
      const char c = s[++i];
      out += c == 'n' ? '\n' : c == 't' ? '\t' : c;
    } else {
      out += s[i];
    }
  }
  return out;
}

std::vector<Case> manifest() {
  std::ifstream in(kManifest);
  std::vector<Case> out;
  std::string row;
  for (int n = 1; std::getline(in, row); ++n) {
    if (row.empty() || row[0] == '#') continue;
    std::vector<std::string> f;
    std::stringstream ss(row);
    for (std::string field; std::getline(ss, field, '\t');) f.push_back(field);
    if (f.size() != 9) {
      ADD_FAILURE() << kManifest << ":" << n << ": " << f.size() << " fields, expected 9";
      continue;
    }
    if (f[6] == "-") f[6].clear();  // no text: delete_line
    out.push_back({n, f[0], f[1], f[2], f[3], f[4], unescape(f[5]), unescape(f[6]), f[7], f[8]});
  }
  return out;
}

int lineAt(const std::string& text, size_t at) {
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
}

std::vector<std::string> linesOf(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string l; std::getline(ss, l);) out.push_back(l);
  return out;
}

struct Edited {
  std::string text;
  int line = 0;  // the first line the edit changed, in the edited program
  std::string error;
};

std::vector<std::string> split(const std::string& s, const std::string& sep) {
  std::vector<std::string> out;
  size_t from = 0;
  for (size_t at; (at = s.find(sep, from)) != std::string::npos; from = at + sep.size()) out.push_back(s.substr(from, at - from));
  out.push_back(s.substr(from));
  return out;
}

// Where `find` is in `text`: its first occurrence, or with a leading '^' its first at a line's start.
size_t locate(const std::string& text, const std::string& find) {
  if (find.empty() || find[0] != '^') return find.empty() ? std::string::npos : text.find(find);
  const std::string rest = find.substr(1);
  if (text.compare(0, rest.size(), rest) == 0) return 0;
  const size_t at = text.find("\n" + rest);
  return at == std::string::npos ? at : at + 1;
}

// The edit of a case on its base program: replace / replace_all (find -> text), delete_line (the
// line holding find), insert_before / insert_after (text as lines around the line holding find).
// Several edits of one case are separated by ";;" in both fields, applied in order.
Edited applyEdit(const Case& c, const std::string& base) {
  Edited e;
  e.text = base;
  const auto finds = split(c.find, ";;");
  const auto texts = split(c.text, ";;");
  if (texts.size() != finds.size() && !(c.op == "delete_line" && c.text.empty())) {
    e.error = "the find and text fields hold different numbers of edits";
    return e;
  }
  for (size_t k = 0; k < finds.size(); ++k) {
    const std::string find = finds[k][0] == '^' ? finds[k].substr(1) : finds[k];
    const std::string text = k < texts.size() ? texts[k] : "";
    const size_t at = locate(e.text, finds[k]);
    if (at == std::string::npos) {
      e.error = "'" + finds[k] + "' is not in the base program";
      return e;
    }
    const size_t bol = at == 0 || e.text.rfind('\n', at - 1) == std::string::npos ? 0 : e.text.rfind('\n', at - 1) + 1;
    size_t eol = e.text.find('\n', at);
    eol = eol == std::string::npos ? e.text.size() : eol + 1;
    int line = lineAt(e.text, at);
    if (c.op == "replace") {
      e.text.replace(at, find.size(), text);
    } else if (c.op == "replace_all") {
      for (size_t p = e.text.find(find); p != std::string::npos; p = e.text.find(find, p + text.size()))
        e.text.replace(p, find.size(), text);
    } else if (c.op == "delete_line") {
      e.text.erase(bol, eol - bol);
    } else if (c.op == "insert_before") {
      e.text.insert(bol, text + "\n");
    } else if (c.op == "insert_after") {
      e.text.insert(eol, text + "\n");
      line += 1;
    } else {
      e.error = "unknown edit '" + c.op + "'";
      return e;
    }
    if (k == 0) e.line = line;
  }
  return e;
}

// The expected violation's line: edit[+-N], prev:TEXT (the last line at or before the edit holding
// TEXT), next:TEXT (the first at or after it), first:TEXT (the first in the program), last (the
// program's last line).
int expectedLine(const Case& c, const Edited& e) {
  const auto lines = linesOf(e.text);
  const std::string& s = c.line;
  if (s.rfind("edit", 0) == 0) return e.line + (s.size() > 4 ? std::stoi(s.substr(4)) : 0);
  if (s == "last") return static_cast<int>(lines.size());
  const std::string what = s.substr(s.find(':') + 1);
  if (s.rfind("prev:", 0) == 0) {
    for (int l = std::min(e.line, static_cast<int>(lines.size())); l >= 1; --l)
      if (lines[static_cast<size_t>(l - 1)].find(what) != std::string::npos) return l;
  } else if (s.rfind("first:", 0) == 0) {
    for (size_t l = 0; l < lines.size(); ++l)
      if (lines[l].find(what) != std::string::npos) return static_cast<int>(l) + 1;
  } else if (s.rfind("next:", 0) == 0) {
    for (int l = e.line; l <= static_cast<int>(lines.size()); ++l)
      if (lines[static_cast<size_t>(l - 1)].find(what) != std::string::npos) return l;
  }
  return 0;
}

TEST(UnsafeCorpus, CoversEveryDialectAndEveryClassOfEdit) {
  const auto cases = manifest();
  EXPECT_GE(cases.size(), 40u);
  std::map<std::string, std::set<std::string>> kinds;
  std::set<std::string> names;
  for (const auto& c : cases) {
    EXPECT_TRUE(names.insert(c.name).second) << "case " << c.name << " twice";
    EXPECT_NE(std::find(kDialects.begin(), kDialects.end(), c.dialect), kDialects.end()) << c.name;
    kinds[c.dialect].insert(c.kind);
  }
  for (const auto& d : kDialects) {
    EXPECT_TRUE(kinds[d].count("guard")) << d << ": no guard that cannot alarm";
    EXPECT_TRUE(kinds[d].count("motion")) << d << ": no unsafe move";
    EXPECT_TRUE(kinds[d].count("flow")) << d << ": no call or loop";
  }
  // Where a control may read a number without a decimal point in least input increments.
  for (const auto& d : {"fanuc", "haas", "okuma"})
    EXPECT_TRUE(kinds[d].count("number")) << d << ": no number the control reads otherwise";
}

class UnsafeCorpusByDialect : public ::testing::TestWithParam<std::string> {};

TEST_P(UnsafeCorpusByDialect, EachEditFailsCheckAtItsLineAndTheBasePasses) {
  const std::string dialect = GetParam();
  const fs::path dir = test::freshDir("UnsafeCorpus_" + dialect);
  auto p = [&](const std::string& name) { return (dir / name).string(); };
  std::map<std::string, std::string> base;  // cycle -> program text
  auto check = [&](const std::string& prog, const std::string& cycle) {
    return sh("check " + prog + " --dialect " + dialect + " --machine " + kMachine + " --plan " + p(cycle + ".json"));
  };
  int ran = 0;
  for (const Case& c : manifest()) {
    if (c.dialect != dialect) continue;
    SCOPED_TRACE(kManifest + ":" + std::to_string(c.manifest_line) + ": " + c.name);
    if (!base.count(c.cycle)) {
      ASSERT_EQ(sh("plan --cycle " + c.cycle + " --machine " + kMachine + " -o " + p(c.cycle + ".json")).code, 0);
      const std::string prog = p(c.cycle + ".base");
      ASSERT_EQ(sh("generate --plan " + p(c.cycle + ".json") + " --dialect " + dialect + " -o " + prog).code, 0);
      // What rotacal writes passes, with the plan (the dialect's rules too) and without it.
      const auto ok = check(prog, c.cycle);
      ASSERT_EQ(ok.code, 0) << ok.out;
      const auto bare = sh("check " + prog + " --dialect " + dialect + " --machine " + kMachine);
      ASSERT_EQ(bare.code, 0) << bare.out;
      base[c.cycle] = slurp(prog);
    }
    const Edited e = applyEdit(c, base[c.cycle]);
    ASSERT_TRUE(e.error.empty()) << e.error;
    ASSERT_NE(e.text, base[c.cycle]);
    const int line = expectedLine(c, e);
    ASSERT_GT(line, 0) << "no line '" << c.line << "'";
    const std::string prog = p(c.name + ".nc");
    std::ofstream(prog, std::ios::binary) << e.text;
    const auto r = check(prog, c.cycle);
    EXPECT_EQ(r.code, 1) << r.out;
    // stdout: FILE:LINE: problem, one line each.
    const std::string at = prog + ":" + std::to_string(line) + ": ";
    bool found = false;
    for (const auto& l : linesOf(r.out))
      if (l.rfind(at, 0) == 0 && l.find(c.message) != std::string::npos) found = true;
    EXPECT_TRUE(found) << "expected '" << at << "..." << c.message << "...' in:\n" << r.out.substr(0, 3000);
    ++ran;
  }
  EXPECT_GT(ran, 0);
}

INSTANTIATE_TEST_SUITE_P(Corpus, UnsafeCorpusByDialect, ::testing::ValuesIn(kDialects),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

}  // namespace
}  // namespace rotacal
