// afford tune ...: a study over config keys (Optuna), run by the Python package: `python3 -m afford tune`
// (python/afford/tune_command.py), with this build's package first on its path. Every argument goes to it as given.
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "afford/process_main.hpp"
#include "apps/afford/commands.hpp"

namespace afford {

Command tuneCommand(CLI::App& app, const FrontDoor& door) {
  auto* tune = app.add_subcommand("tune",
                                  "a study over config keys with Optuna (samplers, pruning, workers sharing a journal "
                                  "file): each trial an experiment folder; `afford tune --help` says more");
  tune->allow_extras();
  tune->prefix_command();
  tune->set_help_flag();  // --help goes to the study's own parser
  return {tune, [tune, &door] {
            namespace fs = std::filesystem;
            if (door.config_dir != defaultConfigDir()) {
              std::fprintf(stderr, "afford tune: --config-dir is not passed on: a study's trials take the config "
                           "folder afford.run takes (an experiment file, a path ending in .yaml, names its own)\n");
              return 2;
            }
            const char* env = std::getenv("AFFORD_PYTHON");  // the interpreter (default Debian's, with its packages)
            const std::string python = env && *env ? env : "/usr/bin/python3";
            const fs::path package = AFFORD_PYTHON_BUILD_DIR;
            if (fs::is_regular_file(package / "afford" / "study.py")) {
              const char* old = std::getenv("PYTHONPATH");
              const std::string path = package.string() + (old && *old ? ":" + std::string(old) : "");
              setenv("PYTHONPATH", path.c_str(), 1);
            }
            setenv("AFFORD_TUNE_PROGRAM", door.program.c_str(), 1);  // (the command it names to continue a study)
            std::vector<std::string> args{python, "-m", "afford", "tune"};
            for (const std::string& a : tune->remaining()) args.push_back(a);
            std::vector<char*> argv;
            for (std::string& a : args) argv.push_back(a.data());
            argv.push_back(nullptr);
            // SIGINT and SIGTERM held back across exec until the study's handler is in place (tune_command.py
            // lets them through): one sent while Python starts is neither lost nor a traceback from an import.
            sigset_t stops, before;
            sigemptyset(&stops);
            sigaddset(&stops, SIGINT);
            sigaddset(&stops, SIGTERM);
            sigprocmask(SIG_BLOCK, &stops, &before);
            execv(python.c_str(), argv.data());
            sigprocmask(SIG_SETMASK, &before, nullptr);
            std::fprintf(stderr, "afford tune: cannot run %s (%s): afford tune runs the Python package with Debian's "
                         "python3 (scripts/setup.sh installs it and builds the package, not with --main)\n",
                         python.c_str(), std::strerror(errno));
            return 2;
          }};
}

}  // namespace afford
