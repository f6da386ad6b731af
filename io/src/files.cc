#include "pidlab/io/files.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "pidlab/spec/field.h"

namespace pidlab::io {
namespace {

constexpr std::size_t kBufferBytes = 1 << 16;

std::string Quoted(const std::string& path) { return spec::Quote(path); }

Status IoError(const std::string& what, const std::string& path, int error_number) {
  return Status::IoFailed(what + " " + Quoted(path) + ": " + std::strerror(error_number));
}

std::string FolderOf(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

// A rename is durable once its folder is synced. Some file systems refuse
// fsync on a folder (EINVAL): the rename itself has happened, so that is no
// failure.
Status SyncFolder(const std::string& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return IoError("cannot open the folder", folder, errno);
  const int rc = ::fsync(fd);
  const int saved = errno;
  ::close(fd);
  if (rc != 0 && saved != EINVAL && saved != EROFS) return IoError("cannot sync the folder", folder, saved);
  return Status::Ok();
}

bool WriteAll(int fd, const char* data, std::size_t size, int* error_number) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      *error_number = errno;
      return false;
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

std::string Bytes(std::size_t n) {
  if (n >= (1u << 20) && n % (1u << 20) == 0) return std::to_string(n >> 20) + " MiB";
  if (n >= 1024 && n % 1024 == 0) return std::to_string(n >> 10) + " KiB";
  return std::to_string(n) + " bytes";
}

}  // namespace

Status CheckWritableTarget(const std::string& path) {
  if (path.empty()) return Status::InvalidInput("the output path is empty");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) return Status::InvalidInput(Quoted(path) + " is a directory, not a file");
    if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) return Status::Ok();  // a stream: written directly
    if (!S_ISREG(st.st_mode)) return Status::InvalidInput(Quoted(path) + " is not a regular file");
    if ((st.st_mode & (S_IWUSR | S_IWGRP | S_IWOTH)) == 0 || ::access(path.c_str(), W_OK) != 0)
      return Status::InvalidInput(Quoted(path) + " is read-only");
  } else if (errno != ENOENT) {
    return Status::InvalidInput(Quoted(path) + " cannot be written: " + std::strerror(errno));
  }
  const std::string folder = FolderOf(path);
  if (::stat(folder.c_str(), &st) != 0)
    return Status::InvalidInput("the folder of " + Quoted(path) + " cannot be used: " + std::strerror(errno));
  if (!S_ISDIR(st.st_mode)) return Status::InvalidInput(Quoted(folder) + " is not a folder");
  if (::access(folder.c_str(), W_OK | X_OK) != 0)
    return Status::InvalidInput("the folder of " + Quoted(path) +
                                " cannot be written: " + std::strerror(errno));
  return Status::Ok();
}

AtomicFile::AtomicFile(std::string path, std::string temp_path, int fd)
    : path_(std::move(path)), temp_path_(std::move(temp_path)), fd_(fd) {
  buffer_.reserve(kBufferBytes);
}

AtomicFile::~AtomicFile() {
  if (!published_) Discard();
}

Status AtomicFile::Open(const std::string& path, std::unique_ptr<AtomicFile>* out) {
  if (Status s = CheckWritableTarget(path); !s.ok()) return s;
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode))) {
    // /dev/stdout, a pipe: nothing to rename into place; written as it comes.
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) return IoError("cannot open", path, errno);
    out->reset(new AtomicFile(path, "", fd));
    return Status::Ok();
  }
  const std::filesystem::path p(path);
  std::string pattern =
      (std::filesystem::path(FolderOf(path)) / ("." + p.filename().string() + ".XXXXXX")).string();
  const int fd = ::mkostemp(pattern.data(), O_CLOEXEC);
  if (fd < 0) return IoError("cannot create a temporary file beside", path, errno);
  // The permissions an ordinary new file gets (mkostemp makes it 0600).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  out->reset(new AtomicFile(path, pattern, fd));
  return Status::Ok();
}

void AtomicFile::Fail(const std::string& what, int error_number) {
  if (status_.ok()) status_ = IoError(what, path_, error_number);
}

void AtomicFile::Flush() {
  if (!status_.ok() || buffer_.empty()) {
    buffer_.clear();
    return;
  }
  int error_number = 0;
  if (!WriteAll(fd_, buffer_.data(), buffer_.size(), &error_number)) Fail("cannot write", error_number);
  buffer_.clear();
}

void AtomicFile::Write(std::string_view bytes) {
  if (!status_.ok() || fd_ < 0) return;
  if (buffer_.size() + bytes.size() > kBufferBytes) Flush();
  if (bytes.size() >= kBufferBytes) {
    int error_number = 0;
    if (status_.ok() && !WriteAll(fd_, bytes.data(), bytes.size(), &error_number))
      Fail("cannot write", error_number);
    return;
  }
  buffer_.append(bytes);
}

Status AtomicFile::Prepare() {
  if (prepared_) return status_;
  if (fd_ < 0 && status_.ok()) status_ = Status::IoFailed("the file " + Quoted(path_) + " was closed");
  Flush();
  if (status_.ok() && !temp_path_.empty() && ::fsync(fd_) != 0) Fail("cannot sync", errno);
  if (fd_ >= 0) {
    if (::close(fd_) != 0) Fail("cannot write", errno);
    fd_ = -1;
  }
  if (!status_.ok()) {
    Discard();
    return status_;
  }
  prepared_ = true;
  return status_;
}

Status AtomicFile::Publish() {
  if (!prepared_) return Status::IoFailed("the file " + Quoted(path_) + " was not prepared");
  if (published_) return Status::Ok();
  if (temp_path_.empty()) {  // a stream, written directly
    published_ = true;
    return Status::Ok();
  }
  // A directory or a read-only file that appeared since Open.
  if (Status s = CheckWritableTarget(path_); !s.ok()) {
    Discard();
    return s;
  }
  if (::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    const int saved = errno;
    Discard();
    return IoError("cannot replace", path_, saved);
  }
  published_ = true;
  return SyncFolder(FolderOf(path_));
}

Status AtomicFile::Commit() {
  if (Status s = Prepare(); !s.ok()) return s;
  return Publish();
}

void AtomicFile::Discard() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!temp_path_.empty() && !published_) ::unlink(temp_path_.c_str());
  temp_path_.clear();
}

Status WriteFile(const std::string& path, std::string_view bytes) {
  std::unique_ptr<AtomicFile> file;
  if (Status s = AtomicFile::Open(path, &file); !s.ok()) return s;
  file->Write(bytes);
  return file->Commit();
}

Status WriteFiles(const std::vector<std::pair<std::string, std::string>>& files) {
  // Every target checked before anything is written.
  for (const auto& [path, bytes] : files)
    if (Status s = CheckWritableTarget(path); !s.ok()) return s;
  std::vector<std::unique_ptr<AtomicFile>> staged(files.size());
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (Status s = AtomicFile::Open(files[i].first, &staged[i]); !s.ok()) return s;
    staged[i]->Write(files[i].second);
    if (Status s = staged[i]->Prepare(); !s.ok()) return s;
  }
  // The old files kept under a second name until every new one is in place.
  std::vector<std::string> backups(files.size());
  auto restore = [&](std::size_t published) {
    for (std::size_t j = 0; j < published; ++j) {
      if (!backups[j].empty())
        ::rename(backups[j].c_str(), files[j].first.c_str());
      else
        ::unlink(files[j].first.c_str());
    }
  };
  auto drop_backups = [&] {
    for (const std::string& b : backups)
      if (!b.empty()) ::unlink(b.c_str());
  };
  for (std::size_t i = 0; i < files.size(); ++i) {
    struct stat st {};
    if (::stat(files[i].first.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
    std::string backup = staged[i]->temporary_path() + ".old";
    if (::link(files[i].first.c_str(), backup.c_str()) != 0) {
      const int saved = errno;
      drop_backups();
      return IoError("cannot keep the old file while writing", files[i].first, saved);
    }
    backups[i] = backup;
  }
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (Status s = staged[i]->Publish(); !s.ok()) {
      restore(i);
      drop_backups();
      return s;
    }
  }
  drop_backups();
  return Status::Ok();
}

namespace {

// Removes `path` and everything under it; errors ignored (cleanup).
void RemoveTree(const std::string& path) {
  std::error_code ec;
  std::filesystem::remove_all(path, ec);
}

// Syncs every regular file under `dir`.
Status SyncTree(const std::string& dir) {
  std::error_code ec;
  for (auto it = std::filesystem::recursive_directory_iterator(dir, ec);
       !ec && it != std::filesystem::recursive_directory_iterator(); it.increment(ec)) {
    const std::string p = it->path().string();
    if (it->is_directory(ec)) {
      if (Status s = SyncFolder(p); !s.ok()) return s;
      continue;
    }
    const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return IoError("cannot open", p, errno);
    const int rc = ::fsync(fd);
    const int saved = errno;
    ::close(fd);
    if (rc != 0) return IoError("cannot sync", p, saved);
  }
  if (ec) return Status::IoFailed("cannot list " + Quoted(dir) + ": " + ec.message());
  return SyncFolder(dir);
}

// Moves every entry of `from` into `to`: files replace files of the same
// name, folders merge into folders.
Status MergeInto(const std::string& from, const std::string& to) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(from, ec)) {
    const std::string source = entry.path().string();
    const std::string target = (std::filesystem::path(to) / entry.path().filename()).string();
    struct stat st {};
    const bool target_exists = ::lstat(target.c_str(), &st) == 0;
    if (entry.is_directory(ec) && target_exists && S_ISDIR(st.st_mode)) {
      if (Status s = MergeInto(source, target); !s.ok()) return s;
      continue;
    }
    if (target_exists && S_ISDIR(st.st_mode))
      return Status::InvalidInput(Quoted(target) + " is a directory, not a file");
    if (::rename(source.c_str(), target.c_str()) != 0) return IoError("cannot replace", target, errno);
  }
  if (ec) return Status::IoFailed("cannot list " + Quoted(from) + ": " + ec.message());
  return SyncFolder(to);
}

// Every file the stage would replace that cannot be replaced.
Status CheckTargets(const std::string& from, const std::string& to) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(from, ec)) {
    const std::string target = (std::filesystem::path(to) / entry.path().filename()).string();
    struct stat st {};
    if (::lstat(target.c_str(), &st) != 0) continue;
    if (entry.is_directory(ec)) {
      if (!S_ISDIR(st.st_mode)) return Status::InvalidInput(Quoted(target) + " is a file, not a folder");
      if (Status s = CheckTargets(entry.path().string(), target); !s.ok()) return s;
    } else if (Status s = CheckWritableTarget(target); !s.ok()) {
      return s;
    }
  }
  return Status::Ok();
}

}  // namespace

Status StagedFolder::Create(const std::string& dir, std::unique_ptr<StagedFolder>* out) {
  if (dir.empty()) return Status::InvalidInput("the output folder is empty");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Status::InvalidInput("cannot create the folder " + Quoted(dir) + ": " + ec.message());
  std::string pattern = (std::filesystem::path(dir) / ".pidlab-staging-XXXXXX").string();
  if (!::mkdtemp(pattern.data())) {
    const int saved = errno;
    if (saved == ENOSPC || saved == EIO || saved == EDQUOT)
      return IoError("cannot create a staging folder in", dir, saved);
    return Status::InvalidInput("the folder " + Quoted(dir) + " cannot be written: " + std::strerror(saved));
  }
  out->reset(new StagedFolder(dir, pattern));
  return Status::Ok();
}

std::string StagedFolder::Unstaged(std::string message) const {
  std::error_code ec;
  const std::string absolute_stage = std::filesystem::absolute(stage_, ec).string();
  for (const std::string& from : {absolute_stage, stage_}) {
    if (from.empty()) continue;
    const std::string to = from == stage_ ? dir_ : std::filesystem::absolute(dir_, ec).string();
    for (std::size_t at = message.find(from); at != std::string::npos;
         at = message.find(from, at + to.size()))
      message.replace(at, from.size(), to);
  }
  return message;
}

StagedFolder::~StagedFolder() {
  if (!committed_) RemoveTree(stage_);
}

Status StagedFolder::Commit() {
  if (committed_) return Status::Ok();
  Status s = SyncTree(stage_);
  if (s.ok()) s = CheckTargets(stage_, dir_);
  if (s.ok()) s = MergeInto(stage_, dir_);
  if (!s.ok()) return s;  // the destructor removes what is left of the stage
  RemoveTree(stage_);
  committed_ = true;
  return Status::Ok();
}

Status OpenRegularFile(const std::string& path, int* fd) {
  // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer,
  // and a device's open may wait too; a regular file ignores the flag.
  const int opened = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (opened < 0) return Status::InvalidInput(Quoted(path) + " cannot be read: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(opened, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(opened);
    return Status::InvalidInput(Quoted(path) + " is not a regular file");
  }
  const int flags = ::fcntl(opened, F_GETFL);
  if (flags < 0 || ::fcntl(opened, F_SETFL, flags & ~O_NONBLOCK) != 0) {
    const int saved = errno;
    ::close(opened);
    return IoError("cannot read", path, saved);
  }
  *fd = opened;
  return Status::Ok();
}

Status ReadFile(const std::string& path, std::size_t max_bytes, std::string* text) {
  int fd = -1;
  if (Status s = OpenRegularFile(path, &fd); !s.ok()) return s;
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int saved = errno;
    ::close(fd);
    return IoError("cannot read", path, saved);
  }
  if (static_cast<unsigned long long>(st.st_size) > max_bytes) {
    ::close(fd);
    return Status::InvalidInput(Quoted(path) + " is larger than " + Bytes(max_bytes));
  }
  std::string out;
  out.resize(static_cast<std::size_t>(st.st_size));
  std::size_t got = 0;
  while (true) {
    if (got == out.size()) {
      // The file may have grown since fstat: read on, within the bound.
      if (out.size() >= max_bytes + 1) break;
      out.resize(std::min(max_bytes + 1, out.size() + 4096));
    }
    const ssize_t n = ::read(fd, out.data() + got, out.size() - got);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int saved = errno;
      ::close(fd);
      return IoError("cannot read", path, saved);
    }
    if (n == 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  if (got > max_bytes) return Status::InvalidInput(Quoted(path) + " is larger than " + Bytes(max_bytes));
  out.resize(got);
  *text = std::move(out);
  return Status::Ok();
}

}  // namespace pidlab::io
