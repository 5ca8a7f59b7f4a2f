#pragma once
// One rule for every option that names a file or folder a program writes (sensornet launch
// --report and --log-dir, sensornet report --html and --csv, fusion_center serve --report,
// coordinator plan --out and serve --state): the folders on the way that do not exist yet are
// made, as `mkdir -p` would (mode 0755 less the umask), but never where someone else could swap
// them. Every folder made must come out a real directory (never a symbolic link), owned by you
// and writable by nobody else, as the launcher's scratch folder is checked; one that another user
// made first (a race in /tmp) is refused. The existing folder they are made in must be yours or
// root's and not writable by others, unless it is sticky as /tmp is (then nobody else can rename
// or remove what is made in it). Folders that exist already are taken as they are: the file
// checks of each program (a regular file or nothing, in a folder where a file can be created)
// still apply.
//
//   makeParentFolders("runs/new/report.json", "--report");  // makes runs/ and runs/new/
//   makeFolders("runs/new/tables", "--csv");                // makes the folder itself too
//   // refused: InputError "--report runs/new/report.json: expected ... (runs is a symbolic link)"

#include <filesystem>
#include <optional>
#include <string>

namespace sensornet {

// Why `dir` is not a private directory of this user (a real directory, not a symbolic link,
// owned by the effective user, not writable by group or others), or nullopt if it is one.
[[nodiscard]] std::optional<std::string> privateDirectoryProblem(const std::filesystem::path& dir);

// Makes `dir` and the folders above it that are missing, under the rule above; throws
// InputError("<option> <dir>", ...) naming the folder and what is wrong.
void makeFolders(const std::filesystem::path& dir, const std::string& option);

// makeFolders for the folder that holds `file` (nothing to do for a bare file name).
void makeParentFolders(const std::filesystem::path& file, const std::string& option);

}  // namespace sensornet
