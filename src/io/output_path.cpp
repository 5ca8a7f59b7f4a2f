#include "sensornet/io/output_path.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;

std::string modeText(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof text, "%04o", static_cast<unsigned>(mode & 07777));
  return text;
}

// Why new folders must not be made in the existing folder `dir`, or nullopt.
std::optional<std::string> shareProblem(const fs::path& dir) {
  struct stat info {};
  if (::stat(dir.c_str(), &info) != 0) {
    return dir.string() + " cannot be looked at (" + std::strerror(errno) + ")";
  }
  if (!S_ISDIR(info.st_mode)) return dir.string() + " is not a directory";
  if (info.st_uid != ::geteuid() && info.st_uid != 0) {
    return dir.string() + " belongs to uid " + std::to_string(info.st_uid) +
           ", who could swap the folders made in it";
  }
  const bool sticky = (info.st_mode & S_ISVTX) != 0;
  if ((info.st_mode & S_IWOTH) != 0 && !sticky) {
    return dir.string() + " may be written by anyone and is not sticky (mode " +
           modeText(info.st_mode) + ")";
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> privateDirectoryProblem(const fs::path& dir) {
  struct stat info {};
  if (::lstat(dir.c_str(), &info) != 0) {
    return std::string("it cannot be looked at (") + std::strerror(errno) + ")";
  }
  if (S_ISLNK(info.st_mode)) return std::string("it is a symbolic link");
  if (!S_ISDIR(info.st_mode)) return std::string("it is not a directory");
  if (info.st_uid != ::geteuid()) {
    return "it is owned by uid " + std::to_string(info.st_uid) + ", not by you (uid " +
           std::to_string(::geteuid()) + ")";
  }
  if ((info.st_mode & (S_IWGRP | S_IWOTH)) != 0) {
    return "others may write to it (mode " + modeText(info.st_mode) + ")";
  }
  return std::nullopt;
}

void makeFolders(const fs::path& dir, const std::string& option) {
  fs::path target = fs::absolute(dir).lexically_normal();
  if (!target.has_filename() && target != target.root_path()) target = target.parent_path();
  const auto refuse = [&](const std::string& why) {
    throw InputError(option + " " + dir.string(), "",
                     "a folder that exists or can be made safely: " + why);
  };
  // The folders on the way, from the root down; the first missing one and all below it are made.
  std::vector<fs::path> chain;
  for (fs::path p = target; !p.empty(); p = p.parent_path()) {
    if (!p.relative_path().empty() || chain.empty()) chain.push_back(p);
    if (p == p.root_path()) break;
  }
  bool making = false;
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    const fs::path& folder = *it;
    struct stat info {};
    if (!making && ::stat(folder.c_str(), &info) == 0) {
      if (!S_ISDIR(info.st_mode)) refuse(folder.string() + " is not a directory");
      continue;
    }
    if (!making) {
      if (errno != ENOENT) refuse(folder.string() + ": " + std::strerror(errno));
      if (const auto problem = shareProblem(folder.parent_path())) refuse(*problem);
      making = true;
    }
    if (::mkdir(folder.c_str(), 0755) != 0 && errno != EEXIST) {
      refuse("cannot make " + folder.string() + " (" + std::strerror(errno) + ")");
    }
    // Made by us, or by someone quicker (EEXIST): either way it must be ours alone.
    if (const auto problem = privateDirectoryProblem(folder)) {
      refuse("the folder " + folder.string() + " was to be made, but " + *problem);
    }
  }
}

void makeParentFolders(const fs::path& file, const std::string& option) {
  const fs::path folder = file.parent_path();
  if (folder.empty()) return;
  try {
    makeFolders(folder, option);
  } catch (const InputError& e) {
    throw InputError(option + " " + file.string(), "", e.expected());
  }
}

}  // namespace sensornet
