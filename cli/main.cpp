// Entry point of the `texgrad` command: parses subcommands and turns errors into one clear line.
#include <CLI/CLI.hpp>
#include <iostream>

int main(int argc, char** argv) {
  CLI::App app{"texgrad: gradient-domain processing of surface signals inside a texture atlas"};
  app.require_subcommand(1);
  CLI11_PARSE(app, argc, argv);
  return 0;
}
