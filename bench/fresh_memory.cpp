// What fresh memory costs on this machine: maps N MiB, writes every byte, unmaps it, three times,
// with or without transparent huge pages. The kernel zeroes each page on its first write; on a
// paravirtualised VM that fault is the costly part (BENCHMARKS.md, "Scale").
// Usage: g++ -O2 bench/fresh_memory.cpp -o /tmp/fresh_memory
//        /usr/bin/time -f "%e s wall, %U s user, %S s sys" /tmp/fresh_memory 1024 huge   (or: small)
#include <sys/mman.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s MIB huge|small\n", argv[0]);
    return 2;
  }
  const size_t bytes = size_t(std::strtoul(argv[1], nullptr, 10)) << 20;
  const bool huge = std::string(argv[2]) == "huge";
  for (int round = 0; round < 3; ++round) {
    void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) return 1;
    if (huge) madvise(p, bytes, MADV_HUGEPAGE);
    std::memset(p, 1, bytes);
    munmap(p, bytes);
  }
  return 0;
}
