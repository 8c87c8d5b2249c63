#include "ui/gui/error_advice.hpp"

#include <exception>
#include <stdexcept>

#include "acquisition/capture.hpp"
#include "drivers/scpi_client.hpp"
#include "drivers/transport.hpp"

namespace piezo::gui {

namespace {
bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }
}  // namespace

const char* kind_name(ErrorKind k) {
  switch (k) {
    case ErrorKind::Connection:
      return "connection error";
    case ErrorKind::Instrument:
      return "instrument error";
    case ErrorKind::File:
      return "file error";
    case ErrorKind::Input:
      return "input error";
    case ErrorKind::Attention:
      return "attention";
    case ErrorKind::Other:
      break;
  }
  return "error";
}

Problem problem_from_current_exception(const std::string& stage) {
  Problem p;
  p.stage = stage;
  try {
    throw;
  } catch (const drivers::TransportError& e) {
    p.kind = ErrorKind::Connection;
    p.message = e.what();
  } catch (const drivers::InstrumentError& e) {
    p.kind = ErrorKind::Instrument;
    p.message = e.what();
  } catch (const acq::CaptureError& e) {
    p.kind = ErrorKind::File;
    p.message = e.what();
  } catch (const std::invalid_argument& e) {
    p.kind = ErrorKind::Input;
    p.message = e.what();
  } catch (const std::exception& e) {
    p.message = e.what();
  } catch (...) {
    p.message = "unknown error";
  }
  p.advice = advice_for(p.kind, stage);
  return p;
}

std::string advice_for(ErrorKind kind, const std::string& stage) {
  switch (kind) {
    case ErrorKind::Connection:
      return "Check that the instruments are on and reachable: tcp://HOST:PORT is the AWG's raw "
             "SCPI socket (usually 5025) and the DAQ answers on PORT+1 unless its own address is "
             "given; for usbtmc:// check the cable, VID:PID and the udev rule. Press Connect to "
             "retry, or use 'sim' for the simulated bench.";
    case ErrorKind::Instrument:
      return "The instrument refused a setting (its error text is above). Check the plan against "
             "its limits (sample rate, record length, amplitude), then Connect again; the error "
             "queue is read after every configuration step.";
    case ErrorKind::File:
      return "Open a piezo-capture/1 file written by 'piezobench measure' or by this program "
             "('piezobench capture info FILE' shows what a file holds).";
    case ErrorKind::Input:
      if (starts_with(stage, "connect"))
        return "Use 'sim', tcp://HOST:PORT or usbtmc://VID:PID[/SERIAL] (a USB bench needs the "
               "DAQ's address too).";
      if (stage == "simulated effects")
        return "Write effects as NAME=VALUE separated by commas, e.g. series_resistance=15; "
               "disturbances as "
               "offset=V,hum=V,mains=50|60,pink=PCT,drift=PCT,step=PCT@SHOT,jitter=SAMPLES.";
      return "Correct the value named above in the plan and run again.";
    case ErrorKind::Other:
    case ErrorKind::Attention:
      break;
  }
  if (starts_with(stage, "estimate"))
    return "The record holds no usable transient: check the excitation (exp_decay, chirp or "
           "noise), "
           "the record length and that the DAQ is not clipping.";
  if (starts_with(stage, "update"))
    return "Check that the geometry and the nominal material match the tube and that R1 is right.";
  if (starts_with(stage, "export") || starts_with(stage, "png"))
    return "Check that the folder exists and is writable.";
  return "The log below has the stages that ran; try again with more shots, or report the "
         "message with the capture file.";
}

std::vector<Problem> result_problems(const jobs::PipelineResult& r) {
  std::vector<Problem> out;
  for (const auto& st : r.stages) {
    if (st.name == "update" && !st.ran)
      out.push_back({ErrorKind::Attention, "update", st.note,
                     "The model update did not converge. Check the geometry, the nominal "
                     "material and R1; more shots lower the noise on the features; a tube far "
                     "from the nominal material may need the transversely isotropic class."});
    if (st.name == "diagnose" && !st.ran && starts_with(st.note, "failed"))
      out.push_back({ErrorKind::Attention, "diagnose", st.note,
                     "The update above stands. The diagnosis needs at least 3 repeated shots "
                     "of one drive (6 or more to hold some out): raise Shots and run again."});
  }
  for (const auto& w : r.warnings)
    if (starts_with(w, "cancelled"))
      out.push_back(
          {ErrorKind::Attention, "acquire", w,
           "The shots acquired before Cancel are in the capture; replay it or measure again."});
  return out;
}

}  // namespace piezo::gui
