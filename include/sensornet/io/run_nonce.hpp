#pragma once
// The run nonce: what tells one deployment of a run from an earlier one with the same run id,
// where a run's files outlive its processes (a container's volume, a systemd state folder). A
// restarted process resumes from its files (the coordinator's journal, the fusion center's
// episode log); a new deployment must not, and cannot tell by the run id when the run id is a
// default. `--run-nonce` (or SENSORNET_RUN_NONCE) names the deployment; the nonce a process
// started its files under is kept beside them, and files of another nonce are an earlier
// deployment's: the process starts afresh over them instead of resuming.
//
//   if (!writtenUnderNonce(journal, nonce)) { /* an earlier deployment's: start afresh */ }
//   recordNonce(journal, nonce);      // after starting afresh: journal.nonce says `nonce`
//
// An empty nonce (none given) accepts any files, as before nonces existed.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <optional>
#include <string>

namespace sensornet {

// Where the nonce of the files at `path` is kept: `<path>.nonce`.
[[nodiscard]] std::filesystem::path nonceFileOf(const std::filesystem::path& path);
// The nonce the files at `path` were started under; nullopt when none was recorded.
[[nodiscard]] std::optional<std::string> recordedNonce(const std::filesystem::path& path);
// Whether the files at `path` belong to the deployment `nonce`: always when `nonce` is empty,
// else when the nonce recorded beside them is `nonce`.
[[nodiscard]] bool writtenUnderNonce(const std::filesystem::path& path, const std::string& nonce);
// Records `nonce` beside `path` (atomically); removes an older record when `nonce` is empty, so
// that files started without a nonce never pass for another deployment's. Throws
// std::runtime_error when the disk refuses it.
void recordNonce(const std::filesystem::path& path, const std::string& nonce);

// `--run-nonce TEXT`, also read from SENSORNET_RUN_NONCE: one declaration for the programs
// that keep a run's files (coordinator serve --state, fusion_center serve --report).
CLI::Option* addRunNonceOption(CLI::App& command, std::string& nonce, const std::string& files);

}  // namespace sensornet
