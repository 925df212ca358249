// OutputSet: temporaries beside their targets, committed together (output.hpp).
#include "bisect/output.hpp"

#include "bisect/mesh.hpp" // InputError

#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <pthread.h>
#include <string_view>
#include <sys/stat.h>
#include <unistd.h>

namespace bisect {
namespace {

namespace fs = std::filesystem;

// Temporaries not yet committed or removed, reachable from a signal handler:
// each slot holds a heap string that stays alive while the slot points at it.
constexpr std::size_t kSlots = 16384;
std::atomic<const char *> g_pending[kSlots];
// 0: nothing committed; 1: a commit has begun (its renames run, or ran, to
// the end); 2: a signal handler removed the temporaries and is ending the
// process. The handler and commit() each claim the state from 0 once, so
// that a signal taken by another thread (sigprocmask in commit() blocks only
// its own) cannot remove temporaries while commit() renames them: that left
// a new mesh beside the old CSV with exit 130 (cli.outputs, once).
std::atomic<int> g_state{0};
// Temporaries being created (opened, not yet registered in g_pending): the
// handler waits for them, so that none is made and left behind as it ends
// the process (see OutputSet::file).
std::atomic<int> g_creating{0};

// SIGINT, SIGTERM and SIGHUP blocked in this thread while it lives.
class BlockedSignals {
public:
  BlockedSignals() {
    sigset_t block;
    sigemptyset(&block);
    sigaddset(&block, SIGINT);
    sigaddset(&block, SIGTERM);
    sigaddset(&block, SIGHUP);
    ::pthread_sigmask(SIG_BLOCK, &block, &old_);
  }
  ~BlockedSignals() { ::pthread_sigmask(SIG_SETMASK, &old_, nullptr); }
  BlockedSignals(const BlockedSignals &) = delete;
  BlockedSignals &operator=(const BlockedSignals &) = delete;

private:
  sigset_t old_;
};

int take_slot(const char *path) {
  for (std::size_t i = 0; i < kSlots; ++i) {
    const char *expected = nullptr;
    if (g_pending[i].compare_exchange_strong(expected, path))
      return int(i);
  }
  return -1;
}

void release_slot(int slot) {
  if (slot < 0)
    return;
  const char *p = g_pending[std::size_t(slot)].exchange(nullptr);
  delete[] p;
}

char *copy_c_string(const std::string &s) {
  char *p = new char[s.size() + 1];
  std::memcpy(p, s.c_str(), s.size() + 1);
  return p;
}

// The file a symbolic link finally names (the path itself when no link).
std::string follow_links(const std::string &path) {
  fs::path p(path);
  for (int depth = 0; depth < 40; ++depth) {
    struct stat st;
    if (::lstat(p.c_str(), &st) != 0 || !S_ISLNK(st.st_mode))
      return p.string();
    std::error_code ec;
    fs::path to = fs::read_symlink(p, ec);
    if (ec)
      throw InputError(path, "cannot follow the symbolic link: " + ec.message());
    p = to.is_absolute() ? to : p.parent_path() / to;
  }
  throw InputError(path, "too many levels of symbolic links");
}

// Same file: same device and inode when both exist, else the same absolute
// path once links in its directories are resolved.
bool same_file(const std::string &a, const std::string &b) {
  struct stat sa, sb;
  const bool ea = ::stat(a.c_str(), &sa) == 0, eb = ::stat(b.c_str(), &sb) == 0;
  if (ea && eb)
    return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (ea != eb)
    return false;
  std::error_code e1, e2;
  const fs::path ca = fs::weakly_canonical(a, e1), cb = fs::weakly_canonical(b, e2);
  return !e1 && !e2 && ca == cb;
}

// ".<name>.<pid>.<n>.tmp" with <name> cut so the whole stays within NAME_MAX.
std::string temporary_name(const std::string &target, unsigned counter) {
  const fs::path p(target);
  char tail_buf[64];
  std::snprintf(tail_buf, sizeof tail_buf, ".%ld.%u.tmp", long(::getpid()), counter);
  const std::string tail = tail_buf;
  std::string base = p.filename().string();
  const std::size_t room = NAME_MAX - 1 - tail.size();
  if (base.size() > room)
    base.resize(room);
  std::string name(1, '.');
  name += base;
  name += tail;
  return (p.parent_path() / name).string();
}

} // namespace

std::string write_failure(int err) {
  if (err == 0)
    return "I/O error";
  std::string s = std::strerror(err);
  if (!s.empty())
    s[0] = char(std::tolower(static_cast<unsigned char>(s[0])));
  return s;
}

bool remove_pending_outputs() noexcept {
  int open = 0;
  if (!g_state.compare_exchange_strong(open, 2))
    return false;
  while (g_creating.load() != 0)
    ; // another thread is registering the file it just made
  for (std::size_t i = 0; i < kSlots; ++i)
    if (const char *p = g_pending[i].load())
      ::unlink(p);
  return true;
}

bool outputs_committed() noexcept {
  return g_state.load() == 1;
}

OutputSet::OutputSet(std::vector<std::string> inputs, bool force)
    : inputs_(std::move(inputs)), force_(force) {}

OutputSet::~OutputSet() {
  for (Output &o : outputs_) {
    if (!committed_ && !o.temp.empty())
      ::unlink(o.temp.c_str());
    release_slot(o.slot);
  }
}

int OutputSet::add(const std::string &path) {
  if (path.empty())
    throw InputError(path, "empty output file name");
  Output o;
  o.name = path;
  // /dev/stdout, /dev/fd/N and the like name whatever the descriptor is (a
  // pipe, a terminal, the file a shell redirected to): always written into,
  // never followed, replaced or removed.
  const bool system = path.rfind("/dev/", 0) == 0 || path.rfind("/proc/", 0) == 0;
  o.target = system ? path : follow_links(path);
  struct stat st;
  const bool exists = ::stat(o.target.c_str(), &st) == 0;
  if (system && !exists)
    throw InputError(path, "cannot write: " + write_failure(errno));
  for (const std::string &in : inputs_)
    if (!in.empty() && same_file(in, o.target))
      throw InputError(path, "is also an input of this command (" + in +
                                 "); refusing to overwrite it, choose another output name");
  if (exists) {
    if (S_ISDIR(st.st_mode))
      throw InputError(path, "cannot write: it is a directory");
    if (S_ISBLK(st.st_mode))
      throw InputError(path, "cannot write: it is a block device");
    if (S_ISSOCK(st.st_mode))
      throw InputError(path, "cannot write: it is a socket");
    o.direct = system || !S_ISREG(st.st_mode); // FIFO, character device: written into
  }
  if (!o.direct) {
    if (fs::path(o.target).filename().string().size() > NAME_MAX)
      throw InputError(path, "cannot write: file name too long");
    for (const Output &other : outputs_)
      if (!other.direct && same_file(other.target, o.target))
        throw InputError(path,
                         "is also the output " + other.name + "; give each output its own name");
    if (exists && !force_)
      throw InputError(path, "already exists (use --force to overwrite)");
    fs::path dir = fs::path(o.target).parent_path();
    if (dir.empty())
      dir = ".";
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
      throw InputError(path, "cannot write: directory " + dir.string() + " does not exist");
    if (::access(dir.c_str(), W_OK) != 0)
      throw InputError(path, "cannot write: directory " + dir.string() + " is not writable");
  } else if (::access(o.target.c_str(), W_OK) != 0) {
    throw InputError(path, "cannot write: " + write_failure(errno));
  }
  outputs_.push_back(std::move(o));
  return int(outputs_.size() - 1);
}

const std::string &OutputSet::file(int handle) {
  Output &o = outputs_.at(std::size_t(handle));
  if (o.direct)
    return o.target;
  if (!o.temp.empty())
    return o.temp;
  struct stat st;
  const bool replaces = ::stat(o.target.c_str(), &st) == 0;
  static std::atomic<unsigned> counter{0};
  for (int attempt = 0; attempt < 100; ++attempt) {
    std::string temp = temporary_name(o.target, counter++);
    char *registered = copy_c_string(temp);
    // Made and registered with the signals blocked in this thread, and
    // counted in g_creating for a handler running in another: a signal
    // either stops the run before the file exists, or removes it.
    int fd, open_errno;
    {
      const BlockedSignals blocked;
      ++g_creating;
      if (g_state.load() == 2) {
        --g_creating;
        for (;;)
          ::pause(); // a signal handler is ending the process
      }
      fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      open_errno = errno;
      o.slot = fd < 0 ? -1 : take_slot(registered);
      --g_creating;
    }
    if (fd < 0) {
      delete[] registered;
      if (open_errno == EEXIST)
        continue;
      throw InputError(o.name, "cannot write: " + write_failure(open_errno));
    }
    if (o.slot < 0) {
      delete[] registered;
      ::close(fd);
      ::unlink(temp.c_str());
      throw InputError(o.name, "cannot write: too many output files");
    }
    if (replaces)
      (void)::fchmod(fd, st.st_mode & 07777); // keep the replaced file's mode
    ::close(fd);
    o.temp = std::move(temp);
    return o.temp;
  }
  throw InputError(o.name, "cannot write: no free temporary file name beside it");
}

void OutputSet::commit() {
  std::string failure;
  {
    const BlockedSignals blocked;
    int state = 0;
    if (!g_state.compare_exchange_strong(state, 1) && state == 2)
      for (;;)
        ::pause(); // a signal handler is removing the temporaries and ending the process
    for (Output &o : outputs_) {
      if (o.direct || o.temp.empty())
        continue;
      // After a failed rename (which nothing short of a vanished directory
      // causes) the rest are not renamed either.
      if (!failure.empty() || ::rename(o.temp.c_str(), o.target.c_str()) != 0) {
        if (failure.empty())
          failure = o.name + ": cannot write: " + write_failure(errno);
        ::unlink(o.temp.c_str());
      }
      o.temp.clear();
      release_slot(o.slot);
      o.slot = -1;
    }
    committed_ = true;
  }
  if (!failure.empty())
    throw InputError("", failure);
}

} // namespace bisect
