#include "output.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace crumple::app {

namespace fs = std::filesystem;

namespace {

constexpr const char* kLongestName = "frame_00000.obj.partial";  // longest file written in --out

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// Empty if every component fits NAME_MAX and the longest file path fits PATH_MAX.
std::string check_lengths(const fs::path& dir) {
  for (const fs::path& part : dir) {
    if (part.native().size() > NAME_MAX) {
      return "--out: a folder name has " + std::to_string(part.native().size()) + " bytes, more than " +
             std::to_string(NAME_MAX);
    }
  }
  std::error_code ec;
  const std::size_t length = fs::absolute(dir, ec).native().size() + 1 + std::strlen(kLongestName);
  if (ec || length >= PATH_MAX) {
    return "--out: the path is too long (" + std::to_string(length) + " bytes with its file names, limit " +
           std::to_string(PATH_MAX - 1) + ")";
  }
  return {};
}

// Checks an existing folder's entries; with `force` removes the owned ones.
std::string clear_owned(const fs::path& dir, bool force) {
  std::error_code ec;
  std::vector<fs::path> owned;
  std::size_t entries = 0;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    ++entries;
    const std::string name = entry.path().filename().string();
    if (!owned_name(name)) continue;
    if (entry.symlink_status(ec).type() == fs::file_type::directory) {
      return "--out: " + entry.path().string() + " is a folder; crumple writes a file of that name";
    }
    owned.push_back(entry.path());
  }
  if (ec) return "--out: cannot list " + dir.string() + ": " + ec.message();
  if (entries > 0 && !force) {
    return "--out " + dir.string() + " is not empty (" + std::to_string(entries) +
           " entries); pass --force to replace the files crumple writes there";
  }
  for (const fs::path& p : owned) {
    if (!fs::remove(p, ec) && ec) return "--out: cannot remove " + p.string() + ": " + ec.message();
  }
  return {};
}

}  // namespace

const char* stats_header() {
  return "frame,time,vertices,edges,triangles,splits,restores,mass,px,py,pz,kinetic,max_strain,step_ms,substeps";
}

std::string stats_row(int frame, const Sheet& sheet, const FrameEvents& ev) {
  char buf[512];
  const SheetStats& t = sheet.stats();
  std::snprintf(buf, sizeof buf, "%d,%.6f,%d,%d,%d,%d,%d,%.17g,%.17g,%.17g,%.17g,%.9g,%.9g,%.4f,%d",
                frame, sheet.time(), t.vertices, t.edges, t.triangles, ev.splits, ev.restores, t.mass,
                t.momentum[0], t.momentum[1], t.momentum[2], t.kinetic, t.max_strain, ev.steps_ms, ev.steps);
  return buf;
}

bool owned_name(const std::string& full) {
  const std::string name = ends_with(full, ".partial") ? full.substr(0, full.size() - 8) : full;
  if (name == "stats.csv" || name == "final.obj") return true;
  if (name.size() != 15 || name.rfind("frame_", 0) != 0 || !ends_with(name, ".obj")) return false;
  return name.find_first_not_of("0123456789", 6) == 11;
}

std::string prepare_out(const fs::path& dir, bool force) {
  if (std::string why = check_lengths(dir); !why.empty()) return why;
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (fs::exists(status)) {
    if (!fs::is_directory(status)) return "--out " + dir.string() + " exists and is not a folder";
    if (std::string why = clear_owned(dir, force); !why.empty()) return why;
  } else {
    fs::create_directories(dir, ec);
    if (ec) return "--out: cannot create " + dir.string() + ": " + ec.message();
  }
  if (::access(dir.c_str(), W_OK | X_OK) != 0) {
    return "--out: cannot write in " + dir.string() + ": " + std::strerror(errno);
  }
  return {};
}

AtomicFile::AtomicFile(fs::path path) : path_(std::move(path)), temp_(path_.string() + ".partial") {
  if (::unlink(temp_.c_str()) != 0 && errno != ENOENT) fail(errno);
  const int fd = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  if (fd < 0) fail(errno);
  file_ = ::fdopen(fd, "w");
  if (!file_) {
    const int error = errno;
    ::close(fd);
    fail(error);
  }
}

AtomicFile::~AtomicFile() {
  if (!file_) return;
  std::fclose(file_);
  ::unlink(temp_.c_str());
}

void AtomicFile::flush() {
  if (std::ferror(file_) || std::fflush(file_) != 0) fail(errno);
}

void AtomicFile::commit() {
  flush();
  std::FILE* file = file_;
  file_ = nullptr;
  if (std::fclose(file) != 0) {
    const int error = errno;
    ::unlink(temp_.c_str());
    fail(error);
  }
  if (std::rename(temp_.c_str(), path_.c_str()) != 0) {
    const int error = errno;
    ::unlink(temp_.c_str());
    fail(error);
  }
}

void AtomicFile::fail(int error) {
  if (error == 0) error = EIO;  // an earlier failed write set the stream's error flag only
  throw std::runtime_error("cannot write " + path_.string() + ": " + std::strerror(error));
}

}  // namespace crumple::app
