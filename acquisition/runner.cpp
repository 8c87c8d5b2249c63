#include "acquisition/runner.hpp"

#include "acquisition/capture_file.hpp"
#include "dsp/signal_stats.hpp"
#include "drivers/scpi_client.hpp"

namespace piezo::acq {

namespace {
std::string shot_label(int k, int total) {
  return "shot " + std::to_string(k + 1) + " of " + std::to_string(total);
}
}  // namespace

RunResult run_measurement(Bench& bench, const MeasurementPlan& plan, const std::filesystem::path& out,
                          const RunnerOptions& opt, const std::function<void(const Progress&)>& progress,
                          const std::atomic<bool>* cancel) {
  plan.validate();
  if (!bench.awg || !bench.daq) throw std::invalid_argument("run_measurement: bench has no AWG or DAQ");
  if (!opt.calibration.empty() && !opt.connect_standard)
    throw std::invalid_argument("run_measurement: calibration standards given without a way to connect them");
  // Calibration: every excitation step for each standard, then for the
  // transducer (role Dut); `connect` marks where a standard is connected.
  struct PhaseStep {
    CalibrationStep phase;
    ExcitationSpec step;
    bool connect = false;
  };
  const auto plan_steps = plan.steps();
  std::vector<CalibrationStep> phases = opt.calibration;
  phases.push_back(CalibrationStep{Role::Dut, 0.0, std::nullopt});
  std::vector<PhaseStep> steps;
  for (const auto& ph : phases)
    for (std::size_t i = 0; i < plan_steps.size(); ++i)
      steps.push_back({ph, plan_steps[i], !opt.calibration.empty() && i == 0});
  RunResult res;
  res.capture = out;
  res.shots_planned = static_cast<int>(steps.size()) * plan.shots;

  WriterOptions wo;
  wo.software = opt.software;
  wo.overwrite = opt.overwrite;
  CaptureWriter writer(out, plan.setup, wo);  // destroyed on any exit: keeps every written shot
  // The simulated bench's disturbances (drivers/sim/disturbances.hpp): their
  // settings go to /truth with the rest, what each shot got after each shot.
  const bool disturbed = opt.record_truth && bench.sim && bench.sim->disturbances().any();
  std::vector<drivers::sim::ShotDisturbances> applied;
  if (opt.record_truth && bench.sim) {
    auto numbers = bench.sim->physics().truth();
    const auto& imp = bench.sim->imperfections();
    numbers.emplace_back("channel_skew_s", imp.channel_skew_s);
    numbers.emplace_back("channel_gain", imp.channel_gain);
    numbers.emplace_back("noise_rel_v1", imp.noise_rel[0]);
    numbers.emplace_back("noise_rel_v2", imp.noise_rel[1]);
    numbers.emplace_back("seed", static_cast<double>(bench.sim->seed()));
    std::vector<std::pair<std::string, std::string>> strings = {
        {"physics", bench.sim->physics().description()}};
    if (disturbed) {
      const auto& d = bench.sim->disturbances();
      for (auto& kv : drivers::sim::disturbance_truth(d, bench.sim->channel_offset_v(1),
                                                      bench.sim->channel_offset_v(2)))
        numbers.push_back(std::move(kv));
      strings.emplace_back("disturbances", drivers::sim::to_string(d));
    }
    writer.write_truth(numbers, strings);
  }

  drivers::DaqConfig dc;
  dc.sample_rate_hz = plan.sample_rate_hz;
  dc.record_length = plan.samples;
  dc.pretrigger_samples = plan.pretrigger_samples;
  dc.range_v[0] = dc.range_v[1] = plan.daq_range_v();
  const std::size_t post = plan.samples - plan.pretrigger_samples;

  int k = 0;
  auto report = [&](const std::string& stage) {
    if (progress) progress(Progress{k, res.shots_planned, stage});
  };
  try {
    for (const auto& [phase, step, connect] : steps) {
      if (connect) {  // the standard (or the transducer again) goes to the terminals
        report("connect " + std::string(to_string(phase.role)));
        if (!opt.connect_standard(phase)) {
          res.cancelled = true;
          break;
        }
      }
      drivers::ArbWaveform w;
      w.samples = synthesize(step, plan.sample_rate_hz, post);
      w.sample_rate_hz = plan.sample_rate_hz;
      w.peak_v = step.amplitude_v;
      bool loaded = false;
      for (int rep = 0; rep < plan.shots; ++rep, ++k) {
        if (cancel && cancel->load()) {
          res.cancelled = true;
          break;
        }
        report("configure");
        // The simulated bench's drift and step follow the capture's shots.
        if (bench.sim) bench.sim->set_capture_position(k, res.shots_planned);
        if (!loaded) {
          bench.awg->load(w);
          loaded = true;
        }
        if (connect && rep == 0) {  // a standard was just connected: range channel 2 for it
          dc.range_v[1] = dc.range_v[0];
          if (opt.autorange_standards && phase.role != Role::Dut) {
            report("range " + std::string(to_string(phase.role)));
            bench.daq->configure(dc);
            bench.daq->arm();
            bench.awg->output(true);
            bench.awg->trigger();
            const drivers::DaqRecord probe = bench.daq->fetch(opt.fetch_timeout_s);
            dc.range_v[1] = channel_range_for(probe.v2, dc.range_v[0]);
          }
        }
        drivers::DaqRecord r;
        for (int attempt = 0;; ++attempt) {
          bench.daq->configure(dc);
          report("acquire");
          bench.daq->arm();
          bench.awg->output(true);
          bench.awg->trigger();
          report("fetch");
          r = bench.daq->fetch(opt.fetch_timeout_s);
          // An autoranged standard's channel 2 clipped: the probe saw this
          // bench's offset and hum at one instant, the shot at another (the
          // hum's phase, 1/f wander). The next range up, and the shot again
          // (not stored), up to the drive's own range.
          if (phase.role == Role::Dut || !opt.autorange_standards || attempt >= 4 || dc.range_v[1] >= dc.range_v[0])
            break;
          dsp::ClipDetection c2;
          c2.range_v = r.range_v[1];
          if (!dsp::compute_stats(r.v2, c2).clipped) break;
          dc.range_v[1] = channel_range_for({1.4 * dc.range_v[1]}, dc.range_v[0]);
          report("range " + std::string(to_string(phase.role)) + " raised");
        }

        Shot s;
        s.sample_rate_hz = r.sample_rate_hz;
        s.excitation = step.kind;
        s.amplitude_v = step.amplitude_v;
        if (step.kind == Excitation::ExpDecay) s.decay_per_s = step.decay_per_s;
        if (step.kind == Excitation::Sine) s.frequency_hz = step.frequency_hz;
        if (step.kind == Excitation::Chirp) {
          s.f_start_hz = step.f_start_hz;
          s.f_stop_hz = step.f_stop_hz;
        }
        s.pretrigger_samples = static_cast<std::int64_t>(r.pretrigger_samples);
        s.role = phase.role;
        if (phase.role == Role::Load) {
          s.load_ohm = phase.load_ohm;
          s.load_parallel_f = phase.load_parallel_f;
        }
        // daq_range_v is one full scale for both channels: written only when they agree
        // (an autoranged standard's channel 2 differs; readers then use the flat-run test).
        if (r.range_v[0] == r.range_v[1]) s.daq_range_v = r.range_v[0];
        else s.v1_range_v = r.range_v[0], s.v2_range_v = r.range_v[1];
        s.v1 = std::move(r.v1);
        s.v2 = std::move(r.v2);
        dsp::ClipDetection clip1, clip2;
        clip1.range_v = r.range_v[0];
        clip2.range_v = r.range_v[1];
        bool clipped = dsp::compute_stats(s.v1, clip1).clipped || dsp::compute_stats(s.v2, clip2).clipped;
        report("write");
        writer.append(s);
        ++res.shots_written;
        if (disturbed) {
          applied.push_back(bench.sim->last_disturbances());
          writer.write_truth({}, {}, drivers::sim::disturbance_series(applied));
        }
        if (clipped) {
          res.clipped_shots.push_back(k);
          if (opt.stop_on_clipping) {
            bench.awg->output(false);
            writer.close();
            throw RunError(shot_label(k, res.shots_planned) + " clipped: a channel reached the DAQ range of ±" +
                               std::to_string(dsp::compute_stats(s.v1, clip1).clipped ? dc.range_v[0] : dc.range_v[1]) +
                               " V. The shot is stored (flagged); raise the range or lower the amplitude. " +
                               std::to_string(res.shots_written) + " shot(s) are in " + out.string(),
                           res);
          }
        }
      }
      if (res.cancelled) break;
    }
    bench.awg->output(false);
  } catch (const RunError&) {
    throw;
  } catch (const std::exception& e) {
    try {
      writer.close();
    } catch (...) {
    }
    throw RunError(shot_label(k, res.shots_planned) + " failed: " + e.what() + ". " +
                       std::to_string(res.shots_written) + " earlier shot(s) are safe in " +
                       (res.shots_written > 0 ? out.string() : std::string("(none written)")),
                   res);
  }
  writer.close();
  return res;
}

}  // namespace piezo::acq
