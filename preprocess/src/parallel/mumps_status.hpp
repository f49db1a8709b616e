#pragma once
// mumps_status.hpp (internal): what a MUMPS failure means for the user, from PETSc's message of it ("MUMPS error in
// numerical factorization: INFOG(1)=-9, INFO(2)=1234 ..."): the out-of-memory codes in words and with the ways out.
// No PETSc needed: the text is all it reads.

#include <optional>
#include <string>

namespace flexbody::preprocess::detail {

/// The INFOG(1) status in a PETSc error message about MUMPS, if it names one.
[[nodiscard]] std::optional<int> mumps_status(const std::string& message);

/// What MUMPS status `infog1` means and what to do about it, one sentence without a final period, for the codes a
/// shift-invert factorization can meet (the MUMPS 5.5 user guide, section "Error diagnostics"): memory (-13: an
/// allocation failed; -8, -9, -11, -12, -14, -15: a work array too small for the factor's fill; -17, -20: a
/// communication buffer; -19: the ICNTL(23) cap) and a numerically singular matrix (-10); empty for other codes.
/// `info2` is INFO(2), the size or count that goes with the status where there is one.
[[nodiscard]] std::string mumps_status_words(int infog1, std::optional<long long> info2);

/// `message` followed by the words for the MUMPS status it names, if any ("...; that is: ...").
[[nodiscard]] std::string with_mumps_words(const std::string& message);

}  // namespace flexbody::preprocess::detail
