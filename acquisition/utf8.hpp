#pragma once
// Text read from files other tools wrote (capture attributes: software,
// transducer, material names) goes to terminals, JSON (which must be UTF-8)
// and HDF5 results files. A damaged or Latin-1 string is kept, not refused:
// each byte that does not start a well-formed UTF-8 sequence, and each control
// character other than tab, newline and carriage return (an escape sequence
// would drive the terminal), becomes U+FFFD (the replacement character).
#include <string>
#include <string_view>

namespace piezo::acq {

std::string utf8_or_replaced(std::string_view in);

}  // namespace piezo::acq
