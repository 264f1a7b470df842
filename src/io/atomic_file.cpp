#include "io/atomic_file.h"

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <vector>

#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

namespace ff::io {
namespace fs = std::filesystem;

Status write_file_atomic(const fs::path& path, std::span<const std::uint8_t> bytes) {
  const fs::path tmp = path.string() + fmt::format(".tmp.{}", ::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return io_error(fmt::format("cannot write {}: {}", path.string(), std::strerror(errno)));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t w = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (w < 0) {
      if (errno == EINTR) continue;
      const int e = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      return io_error(fmt::format("cannot write {}: {}", path.string(), std::strerror(e)));
    }
    done += static_cast<std::size_t>(w);
  }
  // fdatasync so that after the rename the new name never points at unwritten blocks (crash safety).
  if (::fdatasync(fd) != 0 || ::close(fd) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    return io_error(fmt::format("cannot write {}: {}", path.string(), std::strerror(e)));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    return io_error(fmt::format("cannot write {}: {}", path.string(), std::strerror(e)));
  }
  return {};
}

Status write_file_atomic(const fs::path& path, std::string_view text) {
  return write_file_atomic(path, std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

AtomicFileWriter::~AtomicFileWriter() {
  if (fd_ >= 0) {
    ::close(fd_);
    ::unlink(tmp_.c_str());
  }
}

Status AtomicFileWriter::fail(int err) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  ::unlink(tmp_.c_str());
  return io_error(fmt::format("cannot write {}: {}", path_.string(), std::strerror(err)));
}

Status AtomicFileWriter::open(const fs::path& path) {
  if (fd_ >= 0) return io_error(fmt::format("cannot write {}: a file is already open", path.string()));
  path_ = path;
  tmp_ = path.string() + fmt::format(".tmp.{}", ::getpid());
  fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) return io_error(fmt::format("cannot write {}: {}", path.string(), std::strerror(errno)));
  return {};
}

Status AtomicFileWriter::write(std::span<const std::uint8_t> bytes) {
  if (fd_ < 0) return io_error(fmt::format("cannot write {}: not open", path_.string()));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t w = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (w < 0) {
      if (errno == EINTR) continue;
      return fail(errno);
    }
    done += static_cast<std::size_t>(w);
  }
  return {};
}

Status AtomicFileWriter::write_at(std::uint64_t offset, std::span<const std::uint8_t> bytes) {
  if (fd_ < 0) return io_error(fmt::format("cannot write {}: not open", path_.string()));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t w = ::pwrite(fd_, bytes.data() + done, bytes.size() - done, static_cast<off_t>(offset + done));
    if (w < 0) {
      if (errno == EINTR) continue;
      return fail(errno);
    }
    done += static_cast<std::size_t>(w);
  }
  return {};
}

Status AtomicFileWriter::commit() {
  if (fd_ < 0) return io_error(fmt::format("cannot write {}: not open", path_.string()));
  if (::fdatasync(fd_) != 0) return fail(errno);
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0 || std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp_.c_str());
    return io_error(fmt::format("cannot write {}: {}", path_.string(), std::strerror(e)));
  }
  return {};
}

Status ensure_writable_dir(const fs::path& dir) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    return io_error(fmt::format("output path {} is not a folder", dir.string()));
  fs::create_directories(dir, ec);
  if (ec) return io_error(fmt::format("cannot create output folder {}: {}", dir.string(), ec.message()));
  if (!fs::is_directory(dir)) return io_error(fmt::format("output path {} is not a folder", dir.string()));
  if (::access(dir.c_str(), W_OK) != 0)
    return io_error(fmt::format("output folder {} is not writable: {}", dir.string(), std::strerror(errno)));
  return {};
}

std::size_t remove_stale_temp_files(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return 0;
  std::vector<std::filesystem::path> stale;
  for (auto it = std::filesystem::recursive_directory_iterator(dir, ec); !ec && it != std::filesystem::recursive_directory_iterator();
       it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const auto at = name.rfind(".tmp.");
    if (at == std::string::npos || !it->is_regular_file(ec)) continue;
    const std::string pid = name.substr(at + 5);
    if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos) continue;
    // kill(pid, 0) fails with ESRCH when no such process exists: the writer is gone for good.
    const long id = std::strtol(pid.c_str(), nullptr, 10);
    if (id > 0 && id != ::getpid() && ::kill(static_cast<pid_t>(id), 0) != 0 && errno == ESRCH) stale.push_back(it->path());
  }
  std::size_t removed = 0;
  for (const auto& p : stale) removed += std::filesystem::remove(p, ec) ? 1 : 0;
  return removed;
}

}  // namespace ff::io
