// tessera-keys: creates a farm's CURVE keypair in a folder (farm.key, the secret, mode 0600;
// farm.pub). Every process of the farm reads the folder (TESSERA_KEYS); a process without the
// secret cannot join a farm whose endpoints leave the host.
#include <cstdio>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "common/net/curve.h"

int main(int argc, char** argv) {
  CLI::App app{"tessera-keys: create the CURVE keys of a Tessera farm"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  std::string dir = "keys";
  bool force = false;
  app.add_option("dir", dir, "folder for farm.key and farm.pub")->envname("TESSERA_KEYS")->capture_default_str();
  app.add_flag("--force", force, "replace existing keys (every process of the farm must then get the new ones)");
  CLI11_PARSE(app, argc, argv);
  try {
    if (std::filesystem::exists(std::filesystem::path(dir) / "farm.key") && !force) {
      tessera::readFarmKeys(dir);  // check them
      std::printf("%s/farm.key exists and is valid; keeping it (--force replaces it)\n", dir.c_str());
      return 0;
    }
    if (force) std::filesystem::remove(std::filesystem::path(dir) / "farm.key");
    tessera::writeFarmKeys(dir, tessera::generateFarmKeys());
    std::printf("wrote %s/farm.key (secret) and %s/farm.pub\n", dir.c_str(), dir.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tessera-keys: %s\n", e.what());
    return 1;
  }
}
