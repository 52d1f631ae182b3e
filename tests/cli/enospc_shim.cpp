// A full disk, simulated: loaded with LD_PRELOAD, this makes writes to regular files fail with
// ENOSPC once PANDORA_ENOSPC_AFTER bytes have been written to regular files by the process (writes
// to terminals and pipes pass). Used by tests/cli/check_transactions.sh where a small tmpfs cannot
// be mounted. With PANDORA_ENOSPC_FILE set, only writes to files whose path contains that text
// count and fail (the disk fills while that file is written, and space is freed afterwards). Covers
// write, writev, pwrite and pwrite64, which libstdc++'s file streams use.
#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <unistd.h>

extern "C" {

static long long g_left = -2;  // -2: not read yet; -1: no limit

static int Limited(int fd, size_t n) {
  struct stat st;
  if (g_left == -2) {
    const char* v = getenv("PANDORA_ENOSPC_AFTER");
    g_left = v ? atoll(v) : -1;
  }
  if (g_left < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return 0;
  const char* only = getenv("PANDORA_ENOSPC_FILE");
  if (only && *only) {
    char link[64], target[4096];
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    const ssize_t n = readlink(link, target, sizeof target - 1);
    if (n <= 0) return 0;
    target[n] = '\0';
    if (!strstr(target, only)) return 0;
  }
  if ((long long)n > g_left) {
    g_left = 0;
    errno = ENOSPC;
    return 1;
  }
  g_left -= (long long)n;
  return 0;
}

ssize_t write(int fd, const void* buf, size_t n) {
  static ssize_t (*real)(int, const void*, size_t);
  if (!real) real = (ssize_t(*)(int, const void*, size_t))dlsym(RTLD_NEXT, "write");
  if (Limited(fd, n)) return -1;
  return real(fd, buf, n);
}

ssize_t writev(int fd, const struct iovec* iov, int count) {
  static ssize_t (*real)(int, const struct iovec*, int);
  if (!real) real = (ssize_t(*)(int, const struct iovec*, int))dlsym(RTLD_NEXT, "writev");
  size_t n = 0;
  for (int i = 0; i < count; ++i) n += iov[i].iov_len;
  if (Limited(fd, n)) return -1;
  return real(fd, iov, count);
}

ssize_t pwrite(int fd, const void* buf, size_t n, off_t offset) {
  static ssize_t (*real)(int, const void*, size_t, off_t);
  if (!real) real = (ssize_t(*)(int, const void*, size_t, off_t))dlsym(RTLD_NEXT, "pwrite");
  if (Limited(fd, n)) return -1;
  return real(fd, buf, n, offset);
}

ssize_t pwrite64(int fd, const void* buf, size_t n, off_t offset) {
  static ssize_t (*real)(int, const void*, size_t, off_t);
  if (!real) real = (ssize_t(*)(int, const void*, size_t, off_t))dlsym(RTLD_NEXT, "pwrite64");
  if (Limited(fd, n)) return -1;
  return real(fd, buf, n, offset);
}

}  // extern "C"
