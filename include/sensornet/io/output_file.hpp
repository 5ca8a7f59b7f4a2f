#pragma once
// Files the launcher writes for the user (the run report, the current-run record), so that a
// result is never lost or misplaced: the path is checked before a run starts (a regular file or
// nothing yet, in an existing folder where a file can be created), and a file is replaced only
// atomically (a temporary file in the same folder, then rename) and only while the path is a
// regular file or nothing: a device, FIFO, directory, socket or symbolic link there is never
// replaced, removed or written through.
//
//   checkOutputFile("/tmp/r/report.json", "--report");    // InputError naming the path
//   replaceFileAtomically("/tmp/r/report.json", doc.dump(2) + "\n");

#include <filesystem>
#include <functional>
#include <ostream>
#include <optional>
#include <string>

namespace sensornet {

// Why `path` cannot take an output file, or nullopt if it can: it must be a regular file or not
// exist, and its folder must exist and let this process create a file in it (tried for real, so
// that /proc, read-only mounts and permissions all count, also for root).
[[nodiscard]] std::optional<std::string> outputFileProblem(const std::filesystem::path& path);
// Throws InputError("<option> <path>", ...) when outputFileProblem finds one.
void checkOutputFile(const std::filesystem::path& path, const std::string& option);

// Writes `text` to a temporary file beside `path`, flushes it to disk and renames it over
// `path`. Throws std::runtime_error when `path` exists and is not a regular file, or when writing
// fails ("cannot write the <what> <path>: No space left on device": the errno of the write that
// failed); the old file is then left as it was, and no temporary file stays behind.
void replaceFileAtomically(const std::filesystem::path& path, const std::string& text,
                           const std::string& what = {});
// The same with the text written by `write` (a report too large to hold: streamed).
void replaceFileAtomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write,
                           const std::string& what = {});

// Removes `path` if it is a regular file (a stale result); leaves anything else alone.
void removeRegularFile(const std::filesystem::path& path);

}  // namespace sensornet
