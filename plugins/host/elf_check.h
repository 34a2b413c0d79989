#pragma once
// Checks a planner file is a shared object for this machine before dlopen sees it. dlopen maps
// a file's segments as its program headers say; a truncated file maps pages past its end, and
// the first touch of one kills the process with SIGBUS. So the headers are read and checked
// against the file size first: ELF magic, this build's class, data encoding and machine,
// ET_DYN, the program and section header tables inside the file, every PT_LOAD segment's bytes
// inside the file. Opened with O_NONBLOCK and checked to be a regular file on the open
// descriptor, so a FIFO or a device never blocks.
#include <string>

#include "core/status.h"

namespace voxplan::internal {

// InvalidArgument "<path>: not a shared object for this machine: <reason>" on refusal.
Status CheckSharedObject(const std::string& path);

}  // namespace voxplan::internal
