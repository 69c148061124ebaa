// afford bus-key FILE: a new random key for a keyed bus (afford/auth.hpp, docs/security.md).
#include <cstdio>
#include <memory>

#include "afford/auth.hpp"
#include "afford/file_lock.hpp"
#include "apps/afford/commands.hpp"

namespace afford {

Command busKeyCommand(CLI::App& app, const FrontDoor&) {
  auto file = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand("bus-key", "write a new random key for a keyed bus to FILE (mode 0600; an "
                                            "existing file is never overwritten)");
  cmd->add_option("file", *file, "the key file to create")->required();
  return {cmd, [file] {
            prepareOutput(*file, "afford bus-key FILE");
            BusKey::writeNew(*file);
            std::printf("%s: a new bus key; give it to every process of the group (--bus-key %s, or "
                        "AFFORD_BUS_KEY=%s)\n",
                        file->c_str(), file->c_str(), file->c_str());
            return 0;
          }};
}

}  // namespace afford
