// rotacal: the command line of contract.md. Exit 0 on success, 1 on bad input or data (one line
// "rotacal: error: FILE:LINE: what is wrong"), 2 on a usage error. Outputs are written whole
// (temporary file + rename) or not at all, and an existing output is kept as FILE.bak.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <stdexcept>

#include "cli/command.hpp"
#include "git_revision.hpp"  // ROTACAL_GIT_REVISION (cli/CMakeLists.txt)

#ifndef ROTACAL_VERSION
#define ROTACAL_VERSION "0.0.0"
#endif

int main(int argc, char** argv) {
  using namespace rotacal;
  CLI::App app{"rotacal: calibrate the rotary axes of five-axis machine tools with the machine's touch probe"};
  app.set_version_flag("--version", std::string("rotacal ") + ROTACAL_VERSION + " (git " + ROTACAL_GIT_REVISION + ")");
  app.require_subcommand(1);
  app.fallthrough();  // global flags (--quiet) also after the subcommand
  Common common;
  app.add_flag("-q,--quiet", common.quiet, "print nothing on success");
  std::vector<Command> commands = cycleCommands(app, common);
  for (auto& c : uncertaintyCommands(app, common)) commands.push_back(c);
  for (auto& c : compensateCommands(app, common)) commands.push_back(c);
  for (auto& c : reportCommands(app, common)) commands.push_back(c);
  for (auto& c : historyCommands(app, common)) commands.push_back(c);
  for (auto& c : checkCommands(app, common)) commands.push_back(c);
  for (auto& c : compTableCommands(app, common)) commands.push_back(c);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version print on stdout; every other parse error is one line on stderr.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "rotacal: usage error: %s (see --help)\n", oneLine(e.what()).c_str());
    return 2;
  }
  try {
    for (const auto& c : commands)
      if (c.sub->parsed()) return c.run();
  } catch (const CLI::ValidationError& e) {
    std::fprintf(stderr, "rotacal: usage error: %s\n", oneLine(e.what()).c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rotacal: error: %s\n", oneLine(e.what()).c_str());
    return 1;
  }
  return 2;
}
