// The pre-dlopen check of a planner file (elf_check.h): header fields read with pread from a
// descriptor, so nothing of the file is mapped before it is known to be whole.
#include "plugins/host/elf_check.h"

#include <elf.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <string>

namespace voxplan::internal {
namespace {

static_assert(sizeof(void*) == 8, "planner plugins are checked as ELFCLASS64");

#if defined(__x86_64__)
constexpr uint16_t kMachine = EM_X86_64;
#elif defined(__aarch64__)
constexpr uint16_t kMachine = EM_AARCH64;
#elif defined(__riscv)
constexpr uint16_t kMachine = EM_RISCV;
#elif defined(__powerpc64__)
constexpr uint16_t kMachine = EM_PPC64;
#elif defined(__s390x__)
constexpr uint16_t kMachine = EM_S390;
#else
#error "add this machine's EM_* value to plugins/host/elf_check.cpp"
#endif

constexpr unsigned char kData =
    __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__ ? ELFDATA2LSB : ELFDATA2MSB;

// Closes the descriptor on every return.
struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) close(fd);
  }
};

bool ReadAt(int fd, void* out, size_t bytes, uint64_t offset) {
  return pread(fd, out, bytes, off_t(offset)) == ssize_t(bytes);
}

// offset + count * entry_size <= size, without overflow.
bool TableInside(uint64_t offset, uint64_t count, uint64_t entry_size, uint64_t size) {
  if (offset > size) return false;
  return count == 0 || entry_size == 0 || count <= (size - offset) / entry_size;
}

// Empty when the header and its tables fit the file; else why not.
std::string CheckHeader(int fd, const Elf64_Ehdr& h, uint64_t size) {
  if (h.e_ident[EI_CLASS] != ELFCLASS64)
    return h.e_ident[EI_CLASS] == ELFCLASS32 ? "a 32-bit ELF file, this voxplan is 64-bit"
                                             : "unknown ELF class";
  if (h.e_ident[EI_DATA] != kData) return "ELF data encoding (byte order) of another machine";
  if (h.e_machine != kMachine)
    return "built for ELF machine " + std::to_string(h.e_machine) + ", this is machine " +
           std::to_string(kMachine);
  if (h.e_type != ET_DYN) return "ELF type " + std::to_string(h.e_type) + " is not ET_DYN";
  if (h.e_phentsize != sizeof(Elf64_Phdr) || h.e_phnum == 0)
    return "no program header table of this ELF class";
  if (!TableInside(h.e_phoff, h.e_phnum, h.e_phentsize, size))
    return "program header table past the end of the file (truncated?)";
  uint64_t sections = h.e_shnum;
  if (h.e_shoff != 0 && sections == 0) {  // more than SHN_LORESERVE: count in section 0
    Elf64_Shdr first{};
    if (!ReadAt(fd, &first, sizeof first, h.e_shoff))
      return "section header table past the end of the file (truncated?)";
    sections = first.sh_size;
  }
  if (h.e_shoff != 0 && (h.e_shentsize != sizeof(Elf64_Shdr) ||
                         !TableInside(h.e_shoff, sections, h.e_shentsize, size)))
    return "section header table past the end of the file (truncated?)";
  return "";
}

// Empty when every loadable segment's file bytes lie inside the file.
std::string CheckSegments(int fd, const Elf64_Ehdr& h, uint64_t size) {
  for (uint64_t i = 0; i < h.e_phnum; ++i) {
    Elf64_Phdr p{};
    if (!ReadAt(fd, &p, sizeof p, h.e_phoff + i * sizeof p))
      return "cannot read program header " + std::to_string(i);
    if (p.p_type != PT_LOAD) continue;
    if (p.p_offset > size || p.p_filesz > size - p.p_offset)
      return "loadable segment " + std::to_string(i) + " ends at byte " +
             std::to_string(p.p_offset + p.p_filesz) + ", past the file's " + std::to_string(size) +
             " (truncated?)";
  }
  return "";
}

std::string Check(const std::string& path) {
  Fd file{open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC)};
  if (file.fd < 0) return "cannot open it";
  struct stat st {};
  if (fstat(file.fd, &st) != 0) return "cannot stat it";
  if (!S_ISREG(st.st_mode)) return "not a regular file";
  const uint64_t size = uint64_t(st.st_size);
  Elf64_Ehdr h{};
  if (size < EI_NIDENT || !ReadAt(file.fd, h.e_ident, EI_NIDENT, 0) ||
      h.e_ident[EI_MAG0] != ELFMAG0 || h.e_ident[EI_MAG1] != ELFMAG1 ||
      h.e_ident[EI_MAG2] != ELFMAG2 || h.e_ident[EI_MAG3] != ELFMAG3)
    return "no ELF magic";
  if (h.e_ident[EI_CLASS] == ELFCLASS64 && size < sizeof h) return "ELF header truncated";
  if (h.e_ident[EI_CLASS] == ELFCLASS64 && !ReadAt(file.fd, &h, sizeof h, 0))
    return "cannot read the ELF header";
  if (std::string why = CheckHeader(file.fd, h, size); !why.empty()) return why;
  return CheckSegments(file.fd, h, size);
}

}  // namespace

Status CheckSharedObject(const std::string& path) {
  const std::string why = Check(path);
  if (why.empty()) return Status::Ok();
  return InvalidArgument(path + ": not a shared object for this machine: " + why);
}

}  // namespace voxplan::internal
