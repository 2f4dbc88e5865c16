// What the host's memory holds: the memory the system says is available, and
// sizes as people write them ("8G", "512M", "1.5G", bytes), the one parser
// of --host-memory.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace opsila {

// Bytes the system says a new process could use now: /proc/meminfo's
// MemAvailable, else the physical memory (physical_memory()).
std::uint64_t available_host_memory();
// Bytes of physical memory (pages x page size).
std::uint64_t physical_memory();
// Bytes of address space left to this process under its soft RLIMIT_AS
// (ulimit -v), less `reserve` for what others (a driver) still map, at
// least 1; 0 when there is no limit.
std::uint64_t address_space_left(std::uint64_t reserve);
// A positive size: a number (a fraction allowed) with an optional binary
// unit K, M, G or T (1K = 1024; "B" or "iB" may follow), else plain bytes.
// Nothing for anything else, for 0, or beyond 2^60 bytes.
std::optional<std::uint64_t> parse_memory_size(const std::string& text);

}  // namespace opsila
