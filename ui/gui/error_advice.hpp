#pragma once
// What went wrong, in the technician's terms, and what to do about it. The
// worker threads classify the exception they caught (by its type and the stage
// it came from); the windows show the message with the advice. Kept apart from
// the windows so that every error path words its advice the same way.
#include <string>
#include <vector>

#include "jobs/pipeline/pipeline.hpp"

namespace piezo::gui {

enum class ErrorKind {
  Connection,  // no instrument at the address, link closed, timeout (drivers::TransportError)
  Instrument,  // the instrument refused a command or answered nonsense (drivers::InstrumentError)
  File,        // a capture that cannot be read (acq::CaptureError)
  Input,       // a bad value in a form or an address (std::invalid_argument)
  Other,       // any other exception
  Attention,   // not an error: a run that finished but needs action (result_problems)
};

struct Problem {
  ErrorKind kind = ErrorKind::Other;
  std::string stage;    // where it happened ("connect", "acquire: shot 3/8", "open capture", ...)
  std::string message;  // the exception's text
  std::string advice;   // what to do
};

// Call inside a catch block: classifies the exception being handled.
Problem problem_from_current_exception(const std::string& stage);

// Advice for a problem of this kind at this stage.
std::string advice_for(ErrorKind kind, const std::string& stage);

// Conditions of a finished run that are not exceptions but need the
// technician's action (an update that did not converge, a failed diagnosis,
// a cancelled acquisition), each with what to do.
std::vector<Problem> result_problems(const jobs::PipelineResult& r);

// "connection error", ..., "attention": the heading a window shows.
const char* kind_name(ErrorKind k);

}  // namespace piezo::gui
