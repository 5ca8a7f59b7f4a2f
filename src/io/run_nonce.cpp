#include "sensornet/io/run_nonce.hpp"

#include <fstream>
#include <sstream>

#include "sensornet/io/output_file.hpp"

namespace sensornet {

namespace fs = std::filesystem;

fs::path nonceFileOf(const fs::path& path) {
  fs::path nonce = path;
  nonce += ".nonce";
  return nonce;
}

std::optional<std::string> recordedNonce(const fs::path& path) {
  std::ifstream in(nonceFileOf(path), std::ios::binary);
  if (!in) return std::nullopt;
  std::string nonce;
  std::getline(in, nonce);
  return nonce;
}

bool writtenUnderNonce(const fs::path& path, const std::string& nonce) {
  return nonce.empty() || recordedNonce(path) == nonce;
}

void recordNonce(const fs::path& path, const std::string& nonce) {
  if (nonce.empty()) {
    removeRegularFile(nonceFileOf(path));
    return;
  }
  replaceFileAtomically(nonceFileOf(path), nonce + "\n", "run nonce");
}

CLI::Option* addRunNonceOption(CLI::App& command, std::string& nonce, const std::string& files) {
  return command
      .add_option("--run-nonce", nonce,
                  "what tells this deployment of the run from an earlier one with the same run "
                  "id (a container orchestrator's id of the deployment; docker/compose.swarm.yaml "
                  "passes the service's id): " +
                      files +
                      " started under another nonce belong to "
                      "an earlier deployment, and are started afresh over instead of resumed. The "
                      "nonce is kept beside them (FILE.nonce). Default: none (any files are this "
                      "run's)")
      ->envname("SENSORNET_RUN_NONCE");
}

}  // namespace sensornet
