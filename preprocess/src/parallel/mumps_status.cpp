#include "mumps_status.hpp"

#include <fmt/format.h>

#include <cstdlib>

namespace flexbody::preprocess::detail {
namespace {

// The integer after `key` in `message` ("INFOG(1)=-9"), if there is one.
std::optional<long long> integer_after(const std::string& message, const std::string& key) {
  const std::size_t at = message.find(key);
  if (at == std::string::npos) return std::nullopt;
  const char* begin = message.c_str() + at + key.size();
  char* end = nullptr;
  const long long value = std::strtoll(begin, &end, 10);
  if (end == begin) return std::nullopt;
  return value;
}

// INFO(2) of -13 is the allocation's size: megabytes, or with a minus sign millions of bytes (MUMPS's convention).
std::string allocation(std::optional<long long> info2) {
  if (!info2) return "memory";
  const long long size = *info2 < 0 ? -*info2 : *info2;
  return fmt::format("{} MB", size);
}

constexpr const char* kWaysOut =
    "a coarser mesh, linear elements (--order 1), more MPI processes (the factor is split over them) or MUMPS's "
    "out-of-core factor (PETSC_OPTIONS=-st_mat_mumps_icntl_22 1)";

}  // namespace

std::optional<int> mumps_status(const std::string& message) {
  if (message.find("MUMPS") == std::string::npos) return std::nullopt;
  const std::optional<long long> code = integer_after(message, "INFOG(1)=");
  if (!code) return std::nullopt;
  return static_cast<int>(*code);
}

std::string mumps_status_words(int infog1, std::optional<long long> info2) {
  switch (infog1) {
    case -13:
      return fmt::format("MUMPS ran out of memory: it could not allocate {} for the factorization; ways out: {}",
                         allocation(info2), kWaysOut);
    case -8:
    case -9:
    case -11:
    case -12:
    case -14:
    case -15:
      return fmt::format("MUMPS's work arrays were too small for the factor's fill; give it more room with "
                         "PETSC_OPTIONS=-st_mat_mumps_icntl_14 100 (percent over its own estimate), or: {}",
                         kWaysOut);
    case -17:
    case -20:
      return "a MUMPS communication buffer was too small; give it more room with PETSC_OPTIONS=-st_mat_mumps_icntl_14 "
             "100 (percent over its estimate)";
    case -19:
      return fmt::format("the factorization needs more memory than MUMPS's cap ICNTL(23) allows; raise the cap "
                         "(PETSC_OPTIONS=-st_mat_mumps_icntl_23 <MB per process>) or: {}",
                         kWaysOut);
    case -10:
      return "MUMPS found the shifted stiffness K - sigma M numerically singular";
    default: return {};
  }
}

std::string with_mumps_words(const std::string& message) {
  const std::optional<int> code = mumps_status(message);
  if (!code) return message;
  const std::string words = mumps_status_words(*code, integer_after(message, "INFO(2)="));
  return words.empty() ? message : message + "; that is: " + words;
}

}  // namespace flexbody::preprocess::detail
