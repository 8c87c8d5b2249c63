#pragma once
// The text of an error as a person reads it: without the internal function
// names the libraries put before their messages ("find_preset: unknown
// material 'x'" -> "unknown material 'x'"). The CLI passes every error message
// through here before printing it (stderr and --json's error.message).
//
// What is removed: at the start of the message or of a clause (after ": ",
// "(", "; "), a class-qualified name ("comedi::Driver::configure: ",
// "redpitaya::Digitizer::arm: ") or one of the library's function names
// (internal_function_names(), kept in step with the sources by
// tests/cli/test_user_message.cpp). Anything else — file names, limits
// quantities such as "tan_delta: ", effect names — is left as it is.
#include <string>
#include <string_view>
#include <vector>

namespace piezo::jobs {

std::string user_message(std::string_view what);

// The snake_case function names the libraries name in their messages.
const std::vector<std::string_view>& internal_function_names();

}  // namespace piezo::jobs
