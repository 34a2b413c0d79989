// The check before dlopen (plugins/host/elf_check.h): a truncated copy of a real planner (which
// dlopen would map past the end of the file: SIGBUS), a text file, an ELF of another class, byte
// order, machine or type, a FIFO and a folder are all refused with the file and the reason, and
// nothing crashes or blocks.
#include <elf.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "plugins/host/plugin_host.h"
#include "tests/support/test_support.h"

namespace voxplan {
namespace {

namespace fs = std::filesystem;

const fs::path kPlanner = fs::path(VOXPLAN_TEST_PLANNER_DIR) / "libvoxplan_planner_minimal.so";

std::string Bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

void Write(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// LoadPlanner refuses `path` as not a shared object, naming the file and `reason`.
void ExpectRefused(const fs::path& path, const std::string& reason) {
  auto planner = LoadPlanner(path.string());
  ASSERT_FALSE(planner.ok()) << path;
  EXPECT_EQ(planner.status().code(), StatusCode::kInvalidArgument);
  const std::string& m = planner.status().message();
  EXPECT_EQ(m.rfind(path.string() + ": not a shared object for this machine: ", 0), 0u) << m;
  EXPECT_NE(m.find(reason), std::string::npos) << m;
}

TEST(PlannerFileCheck, TheRealPlannerPasses) {
  auto planner = LoadPlanner(kPlanner.string());
  EXPECT_TRUE(planner.ok()) << planner.status().message();
}

TEST(PlannerFileCheck, TruncatedCopiesAreRefusedBeforeDlopen) {
  test::TempDir dir("planner_truncated");
  const std::string whole = Bytes(kPlanner);
  ASSERT_GT(whole.size(), 4096u);
  // From one byte short (the section table at the end is cut) to a few bytes.
  for (size_t keep : {whole.size() - 1, whole.size() * 3 / 4, whole.size() / 2, size_t(4096),
                      sizeof(Elf64_Ehdr) + 8, size_t(40), size_t(3)}) {
    const fs::path cut = dir / ("libvoxplan_planner_cut" + std::to_string(keep) + ".so");
    Write(cut, whole.substr(0, keep));
    ExpectRefused(cut, keep < sizeof(Elf64_Ehdr) ? (keep < EI_NIDENT ? "no ELF magic" : "truncated")
                                                 : "truncated");
  }
}

TEST(PlannerFileCheck, ASegmentPastTheEndIsRefusedWithoutASectionTable) {
  test::TempDir dir("planner_segments");
  std::string copy = Bytes(kPlanner);
  Elf64_Ehdr h;
  std::memcpy(&h, copy.data(), sizeof h);
  h.e_shoff = 0;  // no section table to check: only the segments tell it is cut
  h.e_shnum = 0;
  h.e_shstrndx = 0;
  std::memcpy(copy.data(), &h, sizeof h);
  size_t loaded_end = 0;  // where the last loadable segment's bytes end
  for (size_t i = 0; i < h.e_phnum; ++i) {
    Elf64_Phdr p;
    std::memcpy(&p, copy.data() + h.e_phoff + i * sizeof p, sizeof p);
    if (p.p_type == PT_LOAD) loaded_end = std::max<size_t>(loaded_end, p.p_offset + p.p_filesz);
  }
  ASSERT_GT(loaded_end, 4096u);
  const fs::path cut = dir / "libvoxplan_planner_nosections.so";
  Write(cut, copy.substr(0, loaded_end - 1));
  ExpectRefused(cut, "loadable segment");
}

TEST(PlannerFileCheck, OtherFilesAndOtherMachinesAreRefused) {
  test::TempDir dir("planner_not_elf");
  Write(dir / "text.so", "not an ELF file\n");
  ExpectRefused(dir / "text.so", "no ELF magic");
  Write(dir / "empty.so", "");
  ExpectRefused(dir / "empty.so", "no ELF magic");

  const std::string whole = Bytes(kPlanner);
  auto patched = [&](const char* name, size_t offset, std::string bytes) {
    std::string copy = whole;
    copy.replace(offset, bytes.size(), bytes);
    Write(dir / name, copy);
    return dir / name;
  };
  ExpectRefused(patched("class32.so", EI_CLASS, std::string(1, char(ELFCLASS32))), "32-bit");
  const char other_data = whole[EI_DATA] == ELFDATA2LSB ? ELFDATA2MSB : ELFDATA2LSB;
  ExpectRefused(patched("msb.so", EI_DATA, std::string(1, other_data)), "byte order");
  // e_machine 0xbeef, e_type ET_EXEC (little-endian hosts: low byte first).
  ExpectRefused(patched("machine.so", offsetof(Elf64_Ehdr, e_machine), "\xef\xbe"),
                "ELF machine 48879");
  ExpectRefused(patched("exec.so", offsetof(Elf64_Ehdr, e_type), std::string("\x02\x00", 2)),
                "not ET_DYN");
}

TEST(PlannerFileCheck, FifosAndFoldersAreRefusedWithoutBlocking) {
  test::TempDir dir("planner_fifo");
  const fs::path fifo = dir / "libvoxplan_planner_fifo.so";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  ExpectRefused(fifo, "not a regular file");
  fs::create_directory(dir / "folder.so");
  ExpectRefused(dir / "folder.so", "not a regular file");
}

}  // namespace
}  // namespace voxplan
