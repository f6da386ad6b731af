"""The Python module (tools/python/) against the command line: pidlab.evaluate
and pidlab.tune must return the same keys and the same numbers, bit for bit,
as `pidlab evaluate --json` and `pidlab tune --json` of the same case.

Run by ctest (cli.python_module) as
    PYTHONPATH=<build>/python PIDLAB=<build>/bin/pidlab /usr/bin/python3 -m unittest test_pidlab_module
"""

import json
import os
import subprocess
import tempfile
import unittest

import pidlab

PIDLAB = os.environ["PIDLAB"]
PAPER_NM_GAINS = (29.6558, 0.4977, 28.3216)  # Table II, 1/s^2


def cli(*args):
    out = subprocess.run([PIDLAB, *args, "--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


class Evaluate(unittest.TestCase):
    def assertSameResult(self, got, want, ignore=()):
        self.assertEqual(sorted(got), sorted(want))
        for key in want:
            if key not in ignore:
                self.assertEqual(got[key], want[key], key)

    def test_a_plant_by_name_equals_the_cli_json(self):
        got = pidlab.evaluate("double_integrator", PAPER_NM_GAINS)
        want = cli("evaluate", "--plant", "double_integrator", "--gains", "29.6558,0.4977,28.3216")
        self.assertSameResult(got, want)
        self.assertEqual(got["iae"], 1.9151491935602585)

    def test_a_plant_by_coefficients_equals_the_cli_json(self):
        got = pidlab.evaluate(([1.0], [1.0, 0.0, 1.0]), (2, 1, 1.5), loop="sampled", horizon=5)
        want = cli("evaluate", "--num", "1", "--den", "1,0,1", "--gains", "2,1,1.5", "--loop", "sampled",
                   "--horizon", "5")
        self.assertSameResult(got, want)
        self.assertEqual(got["plant"], "custom")

    def test_bounds_are_reported_as_violations_as_by_the_cli(self):
        got = pidlab.evaluate("double_integrator", PAPER_NM_GAINS, max_ms=1.2, derivative_filter_ratio=10)
        want = cli("evaluate", "--plant", "double_integrator", "--gains", "29.6558,0.4977,28.3216", "--max-ms",
                   "1.2", "--derivative-filter-ratio", "10")
        self.assertSameResult(got, want)
        self.assertEqual(len(got["robustness"]["violations"]), 1)
        self.assertIn("1.2", got["robustness"]["violations"][0])

    def test_custom_with_num_and_den_keywords_is_the_same_plant(self):
        a = pidlab.evaluate("custom", (2, 1, 1.5), num=[1], den=[1, 0, 1])
        b = pidlab.evaluate(([1], [1, 0, 1]), (2, 1, 1.5))
        self.assertEqual(a, b)

    def test_disturbance_and_pid_options_equal_the_cli_json(self):
        got = pidlab.evaluate("oscillator", (2, 1, 1.5), loop="sampled", horizon=4, disturbance="square",
                              disturbance_amplitude=0.2, disturbance_period=1, output_limits=(-1, 1.5),
                              anti_windup="back-calculation", derivative_filter=0.01,
                              derivative_on="measurement", integral="trapezoidal")
        want = cli("evaluate", "--plant", "oscillator", "--gains", "2,1,1.5", "--loop", "sampled", "--horizon",
                   "4", "--disturbance", "square", "--disturbance-amplitude", "0.2", "--disturbance-period", "1",
                   "--output-limits", "-1,1.5", "--anti-windup", "back-calculation", "--derivative-filter",
                   "0.01", "--derivative-on", "measurement", "--integral", "trapezoidal")
        self.assertSameResult(got, want)

    def test_a_reference_step_equals_the_cli_json(self):
        got = pidlab.evaluate("stepper", (20.8836, 26.607, 12.4866), reference=2.5)
        want = cli("evaluate", "--plant", "stepper", "--gains", "20.8836,26.607,12.4866", "--reference", "2.5")
        self.assertSameResult(got, want)
        self.assertEqual(got["reference"], 2.5)

    def test_the_nonlinear_motor_gives_the_cli_motor_object(self):
        got = pidlab.evaluate("stepper_nonlinear", (20.8836, 26.607, 12.4866), loop="sampled", dt=1e-4,
                              horizon=0.5, reference=0.01)
        want = cli("evaluate", "--plant", "stepper_nonlinear", "--gains", "20.8836,26.607,12.4866", "--loop",
                   "sampled", "--dt", "1e-4", "--horizon", "0.5", "--reference", "0.01")
        self.assertSameResult(got, want)
        self.assertEqual(got["status"], "ok")
        self.assertFalse(got["motor"]["lost_steps"])
        self.assertGreater(got["motor"]["peak_phase_voltage_v"], 0.0)

    def test_a_plant_with_dead_time_equals_the_cli_json(self):
        got = pidlab.evaluate("custom", (1, 1, 0), num=[1], den=[1, 1], loop="sampled", delay=0.3)
        want = cli("evaluate", "--loop", "sampled", "--plant", "custom", "--num", "1", "--den", "1,1",
                   "--delay", "0.3", "--gains", "1,1,0")
        self.assertSameResult(got, want)
        self.assertEqual(got["spec"]["delay"], 0.3)
        self.assertNotEqual(got["iae"], pidlab.evaluate("custom", (1, 1, 0), num=[1], den=[1, 1],
                                                        loop="sampled")["iae"])

    def test_a_dead_time_on_the_continuous_loop_is_evaluated_and_a_bad_one_refused(self):
        got = pidlab.evaluate("custom", (1, 1, 0), num=[1], den=[1, 1], delay=0.3)
        self.assertTrue(got["stable"])
        with self.assertRaisesRegex(ValueError, "derivative filter"):
            pidlab.evaluate("custom", (1, 1, 0.1), num=[1], den=[1, 1], delay=0.3)
        with self.assertRaisesRegex(ValueError, "delay -1"):
            pidlab.evaluate("custom", (1, 1, 0), num=[1], den=[1, 1], loop="sampled", delay=-1)

    def test_a_chirp_experiment_with_measurement_noise_equals_the_cli_json(self):
        got = pidlab.evaluate("custom", (0, 0, 0), num=[1], den=[1, 2, 1], loop="sampled", horizon=5,
                              disturbance="chirp", disturbance_amplitude=0.5, chirp_band=(0.1, 5),
                              measurement_noise=0.01, seed=3)
        want = cli("evaluate", "--loop", "sampled", "--plant", "custom", "--num", "1", "--den", "1,2,1",
                   "--gains", "0,0,0", "--horizon", "5", "--disturbance", "chirp", "--disturbance-amplitude",
                   "0.5", "--chirp-band", "0.1,5", "--measurement-noise", "0.01", "--seed", "3")
        self.assertSameResult(got, want)
        self.assertEqual(got["spec"]["measurement_noise"], 0.01)
        self.assertEqual(got["spec"]["chirp_band"], [0.1, 5])

    def test_measurement_noise_is_refused_on_the_continuous_loop_and_when_negative(self):
        with self.assertRaisesRegex(ValueError, "measurement_noise 0.01: noise on the measured y needs loop"):
            pidlab.evaluate("linear", (1, 1, 1), measurement_noise=0.01)
        with self.assertRaisesRegex(ValueError, "measurement_noise -1 must be >= 0"):
            pidlab.evaluate("linear", (1, 1, 1), loop="sampled", measurement_noise=-1)

    def test_bad_input_raises_value_error_naming_the_value(self):
        with self.assertRaisesRegex(ValueError, "nope"):
            pidlab.evaluate("nope", (1, 2, 3))
        with self.assertRaisesRegex(ValueError, "kp"):
            pidlab.evaluate("oscillator", (-1, 2, 3))
        with self.assertRaisesRegex(ValueError, "gains"):
            pidlab.evaluate("oscillator", (1, 2))
        with self.assertRaisesRegex(ValueError, "loop"):
            pidlab.evaluate("oscillator", (1, 2, 3), loop="discrete")


    def test_setpoint_weights_equal_the_cli_json(self):
        # MATLAB's PIDF2 example (docs/two_dof.md).
        got = pidlab.evaluate(([1], [1, 0.5, 0.1]), (1.12, 0.23, 1.3), derivative_filter=0.122,
                              setpoint_weights=(0.664, 0.0136))
        want = cli("evaluate", "--num", "1", "--den", "1,0.5,0.1", "--gains", "1.12,0.23,1.3",
                   "--derivative-filter", "0.122", "--setpoint-weights", "0.664,0.0136")
        self.assertSameResult(got, want)
        self.assertEqual(got["spec"]["setpoint_weights"], [0.664, 0.0136])
        with self.assertRaisesRegex(ValueError, "setpoint_weights 1.5,0: each weight must be finite and in"):
            pidlab.evaluate("oscillator", (2, 1, 1.5), setpoint_weights=(1.5, 0))


class Tune(unittest.TestCase):
    def assertSameTune(self, got, want):
        self.assertEqual(sorted(got), sorted(want))
        for key in want:
            if key != "wall_time_s":  # the one value that is not a result
                self.assertEqual(got[key], want[key], key)

    def test_two_dof_equals_the_cli_json(self):
        got = pidlab.tune("oscillator", objective="load-iae", derivative_filter_ratio=10, max_ms=1.6,
                          method="nelder-mead", max_evals=400, two_dof=True)
        want = cli("tune", "--plant", "oscillator", "--objective", "load-iae", "--derivative-filter-ratio", "10",
                   "--max-ms", "1.6", "--method", "nelder-mead", "--max-evals", "400", "--two-dof")
        self.assertSameTune(got, want)
        self.assertTrue(got["two_dof"]["ran"])

    def test_the_default_tune_equals_the_cli_json(self):
        got = pidlab.tune("oscillator", max_evals=400)
        want = cli("tune", "--plant", "oscillator", "--max-evals", "400")
        self.assertSameTune(got, want)
        self.assertTrue(got["stable"])
        self.assertEqual(got["refine"]["verdict"], want["refine"]["verdict"])

    def test_a_method_seed_and_coefficients_equal_the_cli_json(self):
        got = pidlab.tune(([1], [1, 0, 0]), method="paper-nm", seed=5, refine=False, bounds=(0, 20))
        want = cli("tune", "--num", "1", "--den", "1,0,0", "--method", "paper-nm", "--seed", "5", "--refine",
                   "none", "--bounds", "0,20")
        self.assertSameTune(got, want)

    def test_ziegler_nichols_carries_its_rule(self):
        got = pidlab.tune("stepper", method="ziegler-nichols", zn_rule="pessen")
        want = cli("tune", "--plant", "stepper", "--method", "ziegler-nichols", "--zn-rule", "pessen")
        self.assertSameTune(got, want)
        self.assertEqual(got["ziegler_nichols"]["rule"], "pessen")

    def test_a_tuning_rule_with_its_model_equals_the_cli_json(self):
        got = pidlab.tune(([1], [0.2, 1.2, 1]), method="amigo", rule="pi")
        want = cli("tune", "--num", "1", "--den", "0.2,1.2,1", "--method", "amigo", "--rule", "pi")
        self.assertSameTune(got, want)
        self.assertEqual(got["model"]["kind"], "fopdt")
        self.assertTrue(got["model"]["half_rule"])
        self.assertEqual(got["tuning_rule"]["rule"], "pi")
        self.assertEqual(got["spec"]["rule"], "pi")

    def test_the_robust_preset_and_a_robust_set_equal_the_cli_json(self):
        got = pidlab.tune("double_integrator", robust=True, robust_samples=4, robust_spread=0.2, max_evals=600)
        want = cli("tune", "--plant", "double_integrator", "--robust", "--robust-samples", "4",
                   "--robust-spread", "20%", "--max-evals", "600")
        self.assertSameTune(got, want)
        self.assertEqual(got["objective_kind"], "setpoint-load")
        self.assertEqual(got["constraints"]["max_ms"], 1.6)
        self.assertEqual(got["robust_set"]["size"], 5)
        self.assertEqual(got["robustness"]["violations"], [])

    def test_bound_keywords_and_a_filter_ratio_equal_the_cli_json(self):
        got = pidlab.tune("stepper", max_ms=1.4, min_phase_margin=45, derivative_filter_ratio=10, max_evals=400)
        want = cli("tune", "--plant", "stepper", "--max-ms", "1.4", "--min-phase-margin", "45",
                   "--derivative-filter-ratio", "10", "--max-evals", "400")
        self.assertSameTune(got, want)
        self.assertEqual(got["constraints"]["max_ms"], 1.4)
        self.assertEqual(got["constraints"]["derivative_filter_ratio"], 10)
        self.assertLessEqual(got["robustness"]["ms"], 1.4)
        self.assertGreaterEqual(got["robustness"]["phase_margin_deg"], 45)
        self.assertEqual(got["robustness"]["violations"], [])

    def test_an_argument_next_to_robust_overrides_its_part_as_the_flag_does(self):
        got = pidlab.tune("stepper", robust=True, max_ms=1.3, load_weight=2, max_evals=600)
        want = cli("tune", "--plant", "stepper", "--robust", "--max-ms", "1.3", "--load-weight", "2",
                   "--max-evals", "600")
        self.assertSameTune(got, want)
        self.assertEqual(got["objective_kind"], "setpoint-load")
        self.assertEqual(got["load_weight"], 2)
        self.assertEqual(got["constraints"]["max_ms"], 1.3)
        self.assertEqual(got["constraints"]["derivative_filter_ratio"], 10)

    def test_bad_options_raise_value_error(self):
        with self.assertRaisesRegex(ValueError, "simplex"):
            pidlab.tune("oscillator", method="simplex")
        with self.assertRaises(ValueError):
            pidlab.tune("oscillator", bounds=(5, 1))


class Spec(unittest.TestCase):
    """The keywords are the spec's fields: every one reaches the spec, and a
    result's spec runs again to the same result."""

    def test_every_field_is_a_keyword_that_reaches_the_spec(self):
        for which in ("evaluate", "tune"):
            fields = pidlab.spec_fields(which)
            self.assertGreater(len(fields), 30)
            for f in fields:
                with self.subTest(which=which, key=f["key"]):
                    self.assertEqual(f["flag"], "--" + f["key"].replace("_", "-"))
                    spec = pidlab.read_spec(which, **{f["key"]: f["example"]})
                    if which == "tune" and f["key"] == "robust":
                        continue  # the preset changes other fields too
                    self.assertEqual(spec[f["key"]], f["example"])
                    self.assertNotEqual(f["default"], f["example"])

    def test_the_defaults_are_the_commands(self):
        self.assertEqual(pidlab.read_spec("evaluate")["stability_margin"], 1e-9)
        self.assertEqual(pidlab.read_spec("tune")["stability_margin"], 0.01)
        self.assertEqual(pidlab.read_spec("tune", robust=True)["max_time_constant"], 2.5)

    def test_a_results_spec_runs_again_to_the_same_result(self):
        first = pidlab.evaluate("stepper", (20.8836, 26.607, 12.4866), loop="sampled", dt=1e-4, horizon=2,
                                output_limits=(-5, float("inf")))
        again = pidlab.evaluate(**first["spec"])
        self.assertEqual(first, again)
        self.assertEqual(first["spec"]["output_limits"], [-5, "inf"])

    def test_the_spec_equals_the_command_lines(self):
        got = pidlab.evaluate(([1.0], [1.0, 0.5, 0.1]), (1.12, 0.23, 1.3), derivative_filter=0.122)
        want = cli("evaluate", "--num", "1", "--den", "1,0.5,0.1", "--gains", "1.12,0.23,1.3",
                   "--derivative-filter", "0.122")
        self.assertEqual(got["spec"], want["spec"])
        self.assertEqual(got["spec"]["plant"], "custom")

    def test_an_unknown_keyword_is_a_type_error_naming_it(self):
        with self.assertRaisesRegex(TypeError, "horizn"):
            pidlab.evaluate("oscillator", (1, 2, 3), horizn=3)
        with self.assertRaisesRegex(ValueError, "horizon"):
            pidlab.evaluate("oscillator", (1, 2, 3), horizon="long")


class Autotune(unittest.TestCase):
    """pidlab.autotune's keywords are the autotune spec's fields, the flags of
    `pidlab autotune` (spec/autotune_spec.h): one list for both. (The run
    itself, from a log, is integration.autotune.log's.)"""

    def test_every_field_is_a_flag_of_the_command_and_a_keyword_that_reaches_the_spec(self):
        fields = pidlab.spec_fields("autotune")
        self.assertGreaterEqual(len(fields), 18)
        help_text = subprocess.run([PIDLAB, "autotune", "--help"], check=True, capture_output=True,
                                   text=True).stdout
        for f in fields:
            with self.subTest(key=f["key"]):
                self.assertEqual(f["flag"], "--" + f["key"].replace("_", "-"))
                self.assertIn(f["flag"] + " ", help_text)
                spec = pidlab.read_spec("autotune", **{f["key"]: f["example"]})
                self.assertEqual(spec[f["key"]], f["example"])
                self.assertNotEqual(f["default"], f["example"])

    def test_a_bad_keyword_value_is_named_before_the_log_is_read(self):
        with self.assertRaisesRegex(ValueError, "method 'pso'"):
            pidlab.autotune("no.lcmlog", method="pso")
        with self.assertRaisesRegex(ValueError, "^scalar 'q7' is not one of double, q31, q15"):
            pidlab.autotune("no.lcmlog", scalar="q7")
        with self.assertRaisesRegex(ValueError, "needs input_range LO,HI"):
            pidlab.autotune("no.lcmlog", scalar="q15")
        with self.assertRaisesRegex(TypeError, "methd"):
            pidlab.autotune("no.lcmlog", methd="simc")
        with self.assertRaisesRegex(ValueError, "no.lcmlog"):
            pidlab.autotune("no.lcmlog", method="simc")


class Identify(unittest.TestCase):
    """pidlab.identify on numpy arrays against `pidlab identify --csv --json` of the same record."""

    @classmethod
    def setUpClass(cls):
        import numpy as np
        import tempfile
        rng = np.random.default_rng(4)
        n, dt = 300, 0.1
        cls.t = np.arange(n) * dt
        cls.u = np.repeat(rng.uniform(-1.0, 1.0, n // 10), 10)
        cls.u[:5] = 0.0
        # A first-order lag with a fractional delay of 0.25 s, exact under ZOH
        # (a = e^(-dt/Tp1); the held input starts 0.05 s into a sample).
        kp, tp1, td = 1.5, 2.0, 0.25
        y = np.zeros(n)
        state = 0.0
        for k in range(n - 1):
            # input held over [k dt, (k+1) dt), delayed by td: in [k dt, (k+1) dt) the
            # plant sees u[k-3] for 0.05 s then u[k-2] for 0.05 s.
            for value, h in ((cls.u[k - 3] if k >= 3 else 0.0, 0.05), (cls.u[k - 2] if k >= 2 else 0.0, 0.05)):
                a = np.exp(-h / tp1)
                state = a * state + (1 - a) * kp * value
            y[k + 1] = state
        cls.y = y + 0.002 * rng.standard_normal(n) * (np.arange(n) > 0)
        cls.dir = tempfile.mkdtemp()
        cls.csv = os.path.join(cls.dir, "record.csv")
        with open(cls.csv, "w") as f:
            f.write("t,u,y\n")
            for row in zip(cls.t, cls.u, cls.y):
                f.write("%.17g,%.17g,%.17g\n" % row)

    def test_numpy_arrays_give_the_cli_json(self):
        for model in ("p1d", "auto"):
            got = pidlab.identify(self.t, self.u, self.y, model=model)
            want = cli("identify", "--csv", self.csv, "--model", model)
            del want["source"]
            self.assertEqual(got, want, model)
        self.assertEqual(got["auto"]["chosen"], "p1d")
        p = got["parameters"]
        for name, true in (("Kp", 1.5), ("Tp1", 2.0), ("Td", 0.25)):
            self.assertLess(abs(p[name]["value"] - true), 4 * p[name]["standard_error"], name)

    def test_a_non_uniform_record_gives_the_cli_json(self):
        import numpy as np
        # The same samples at times jittered by up to 30 % of dt (the fit is then
        # of another record, but the binding and the CLI must agree on it).
        rng = np.random.default_rng(9)
        t = np.concatenate(([0.0], np.cumsum(0.1 * (1 + rng.uniform(-0.3, 0.3, len(self.t) - 1)))))
        csv = os.path.join(self.dir, "jitter.csv")
        with open(csv, "w") as f:
            f.write("t,u,y\n")
            for row in zip(t, self.u, self.y):
                f.write("%.17g,%.17g,%.17g\n" % row)
        got = pidlab.identify(t, self.u, self.y, model="p1d", starts=3)
        want = cli("identify", "--csv", csv, "--model", "p1d", "--starts", "3")
        del want["source"]
        self.assertEqual(got, want)
        self.assertFalse(got["sampling"]["uniform"])
        self.assertEqual(got["sampling"]["min_interval_s"], np.diff(t).min())
        self.assertEqual(got["sampling"]["max_interval_s"], np.diff(t).max())

    def test_intersample_and_initial_condition_give_the_cli_json(self):
        got = pidlab.identify(self.t, self.u, self.y, model="p1d", starts=3, intersample="foh",
                              initial_condition="estimate")
        want = cli("identify", "--csv", self.csv, "--model", "p1d", "--starts", "3", "--intersample", "foh",
                   "--initial-condition", "estimate")
        del want["source"]
        self.assertEqual(got, want)
        self.assertEqual((got["intersample"], got["initial_condition"], len(got["initial_state"])),
                         ("foh", "estimate", 1))
        got = pidlab.identify(self.t, self.u, self.y, model="p1d", starts=3, u0="estimate", y0=0)
        want = cli("identify", "--csv", self.csv, "--model", "p1d", "--starts", "3", "--u0", "estimate", "--y0", "0")
        del want["source"]
        self.assertEqual(got, want)
        self.assertTrue(got["u0_estimated"])
        with self.assertRaisesRegex(ValueError, "u0 = 'guess'"):
            pidlab.identify(self.t, self.u, self.y, u0="guess")
        with self.assertRaisesRegex(ValueError, "intersample = 'cubic'"):
            pidlab.identify(self.t, self.u, self.y, intersample="cubic")
        with self.assertRaisesRegex(ValueError, "initial_condition = 'rest'"):
            pidlab.identify(self.t, self.u, self.y, initial_condition="rest")

    def test_a_robust_loss_gives_the_cli_json(self):
        y = self.y.copy()
        y[[40, 160, 250]] += 5.0  # three dropouts
        csv = os.path.join(self.dir, "dropouts.csv")
        with open(csv, "w") as f:
            f.write("t,u,y\n")
            for row in zip(self.t, self.u, y):
                f.write("%.17g,%.17g,%.17g\n" % row)
        got = pidlab.identify(self.t, self.u, y, model="p1d", starts=3, loss="cauchy")
        want = cli("identify", "--csv", csv, "--model", "p1d", "--starts", "3", "--loss", "cauchy")
        del want["source"]
        self.assertEqual(got, want)
        self.assertEqual(got["loss"]["downweighted"]["samples"], [40, 160, 250])
        with self.assertRaisesRegex(ValueError, "loss = 'tukey'"):
            pidlab.identify(self.t, self.u, y, loss="tukey")
        with self.assertRaisesRegex(ValueError, "loss_scale = 1 applies"):
            pidlab.identify(self.t, self.u, y, loss_scale=1.0)

    def test_lists_and_options_reach_the_fit(self):
        got = pidlab.identify(list(self.t), list(self.u), list(self.y), model="p1d", starts=3, seed=7, u0=0, y0=0)
        self.assertEqual((got["starts"] - got["arx_start"], got["seed"], got["u0"], got["y0"]), (3, 7, 0, 0))
        self.assertFalse(got["y0_estimated"])

    def test_bad_data_and_arguments_raise_value_error_naming_them(self):
        with self.assertRaisesRegex(ValueError, "too short: 5 samples"):
            pidlab.identify(self.t[:5], self.u[:5], self.y[:5])
        with self.assertRaisesRegex(ValueError, "model = 'p9d'"):
            pidlab.identify(self.t, self.u, self.y, model="p9d")
        with self.assertRaisesRegex(ValueError, "constant input"):
            pidlab.identify(self.t, 0 * self.u, self.y)
        with self.assertRaisesRegex(ValueError, "u must be a sequence"):
            pidlab.identify(self.t, "abc", self.y)
        with self.assertRaisesRegex(ValueError, "starts = 0"):
            pidlab.identify(self.t, self.u, self.y, starts=0)

    def test_a_general_transfer_function_gives_the_cli_json(self):
        got = pidlab.identify(self.t, self.u, self.y, model="tf", poles=1)
        want = cli("identify", "--csv", self.csv, "--model", "tf", "--poles", "1")
        del want["source"]
        self.assertEqual(got, want)
        self.assertEqual((got["model"], got["poles"], got["zeros"]), ("tf", 1, 0))
        self.assertEqual(sorted(got["parameters"]), ["Td", "a0", "b0"])
        # Kp / (1 + Tp1 s) = (Kp / Tp1) / (s + 1 / Tp1).
        p = got["parameters"]
        for name, true in (("b0", 0.75), ("a0", 0.5), ("Td", 0.25)):
            self.assertLess(abs(p[name]["value"] - true), 4 * p[name]["standard_error"], name)
        two = pidlab.identify(self.t, self.u, self.y, model="tf", poles=2, zeros=1)
        self.assertEqual(sorted(two["parameters"]), ["Td", "a0", "a1", "b0", "b1"])

    def test_bad_tf_shapes_raise_value_error_naming_them(self):
        with self.assertRaisesRegex(ValueError, "poles = 7 must be in 1..6"):
            pidlab.identify(self.t, self.u, self.y, model="tf", poles=7)
        with self.assertRaisesRegex(ValueError, "zeros = 2 must be in 0..1"):
            pidlab.identify(self.t, self.u, self.y, model="tf", poles=2, zeros=2)
        with self.assertRaisesRegex(ValueError, "needs poles=N"):
            pidlab.identify(self.t, self.u, self.y, model="tf")
        with self.assertRaisesRegex(ValueError, "apply to model='tf' only"):
            pidlab.identify(self.t, self.u, self.y, model="p1d", poles=2)


class Model(unittest.TestCase):
    """model=FILE and plant="model:FILE": the file `pidlab identify --out`
    writes as the plant, the same as the command line's --model FILE."""

    MODEL = {
        "model": "p1d",
        "parameters": {"Kp": {"value": 1.8, "standard_error": 0.018},
                       "Tp1": {"value": 1.3, "standard_error": 0.023},
                       "Td": {"value": 0.29, "standard_error": 0.008}},
        "transfer_function": {"num": [1.8], "den": [1.3, 1.0], "delay_s": 0.29},
        "covariance": {"ok": True, "message": "",
                       "matrix": [[3.3e-4, 3.1e-4, -6.8e-5], [3.1e-4, 5.2e-4, -1.1e-4], [-6.8e-5, -1.1e-4, 6.4e-5]]},
    }

    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.dir.name, "model.json")
        with open(self.path, "w") as f:
            json.dump(self.MODEL, f)

    def tearDown(self):
        self.dir.cleanup()

    def test_model_keyword_equals_the_cli_and_the_plant_form(self):
        got = pidlab.evaluate(model=self.path, gains=(0.5, 0.4, 0), loop="sampled")
        want = cli("evaluate", "--model", self.path, "--gains", "0.5,0.4,0", "--loop", "sampled")
        self.assertEqual(got, want)
        self.assertEqual(got["spec"]["plant"], "model:" + self.path)
        by_plant = pidlab.evaluate("model:" + self.path, (0.5, 0.4, 0), loop="sampled")
        custom = pidlab.evaluate(([1.8], [1.3, 1.0]), (0.5, 0.4, 0), loop="sampled", delay=0.29)
        self.assertEqual(by_plant["iae"], got["iae"])
        self.assertEqual(custom["iae"], got["iae"])
        self.assertEqual(pidlab.evaluate(**got["spec"]), got)

    def test_tune_draws_the_robust_set_from_the_covariance(self):
        got = pidlab.tune(model=self.path, loop="sampled", horizon=10, robust_samples=4, seed=1, max_evals=40,
                          refine=False)
        want = cli("tune", "--model", self.path, "--loop", "sampled", "--horizon", "10", "--robust-samples", "4",
                   "--seed", "1", "--max-evals", "40", "--refine", "none")
        self.assertEqual(got["robust_set"], want["robust_set"])
        self.assertEqual(got["gains"], want["gains"])
        self.assertEqual(got["robust_set"]["perturbed"], "identified model's parameter covariance")

    def test_a_bad_model_file_is_a_value_error_naming_the_file(self):
        with self.assertRaisesRegex(ValueError, "model file '.*missing.json' cannot be read"):
            pidlab.evaluate(model=os.path.join(self.dir.name, "missing.json"), gains=(1, 1, 0))


class Messages(unittest.TestCase):
    def test_the_package_also_holds_the_lcm_messages(self):
        m = pidlab.lcmt_control_command()
        m.step, m.u = 7, -0.25
        back = pidlab.lcmt_control_command.decode(m.encode())
        self.assertEqual((back.step, back.u), (7, -0.25))


if __name__ == "__main__":
    unittest.main()
