// The `simit` command line: subcommands and their options.
#include "cli.h"

#include <CLI/CLI.hpp>
#include <charconv>
#include <limits>
#include <string>

#include <unistd.h>

#include <cstdio>
#include <iostream>

#include "scene_command.h"
#include "simit/commands.h"
#include "simit/testing.h"
#ifdef SIMIT_HAVE_REPL
#include "simit/debug.h"
#include "terminal.h"
#endif
#ifdef SIMIT_HAVE_DAP
#include "simit/dap.h"
#endif

#ifndef SIMIT_VERSION
#define SIMIT_VERSION "unknown"
#endif

namespace simit::tools {
namespace {

constexpr int kUsageError = 2;

// Where the executor options of `simit run` and `simit test` land: each value parsed once,
// here, into the typed choice the engine receives.
struct ExecutorFlags {
  ExecutorChoice* choice = nullptr;
  bool* stats = nullptr;
  CLI::Option* kind = nullptr;     // --executor: given or not
  CLI::Option* threads = nullptr;  // --threads: given or not
  CLI::Option* cache = nullptr;    // --jit-cache: given or not
};

struct Commands {
  CLI::App* check = nullptr;
  CLI::App* test = nullptr;
  CLI::App* run = nullptr;
  CLI::App* repl = nullptr;
  std::string repl_file;
  CLI::App* debug = nullptr;
  DebugOptions debug_options;
  CLI::App* dap = nullptr;
  CLI::App* partition = nullptr;
  PartitionOptions partition_options;
  CheckOptions check_options;
  std::vector<std::string> test_paths;
  TestCommandOptions test_options;  // how `simit test` runs %! tests and graph sections
  RunOptions run_options;
  SceneOptions scene_options;
  bool no_finite_check = false;  // simit run --no-finite-check (scenes)
  bool distributed = false;      // simit run --distributed (scenes, under mpirun)
  ExecutorFlags run_executor{&run_options.executor, &run_options.jit_stats};
  ExecutorFlags test_executor{&test_options.executor, &test_options.jit_stats};
};

// An option whose value one of simit/executor.h's parsers turns into the choice; CLI11
// reports the parser's error as a usage error ("--executor: unknown executor ...").
template <typename Parse>
CLI::Option* add_parsed(CLI::App& sub, const std::string& names, Parse parse,
                        const std::string& help) {
  const std::string name = names.substr(0, names.find(','));
  return sub.add_option_function<std::string>(
      names,
      [parse, name](const std::string& text) {
        std::string error;
        if (!parse(text, error)) throw CLI::ValidationError(name, error);
      },
      help);
}

// The executor options, defined once for both commands: the same names, checks and words.
// `runs` says what the executor runs; `stats_when` when --jit-stats prints.
void add_executor_options(CLI::App& sub, ExecutorFlags& t, const std::string& runs,
                          const std::string& stats_when) {
  ExecutorChoice& x = *t.choice;
  t.kind =
      add_parsed(
          sub, "--executor,--backend",
          [&x](const std::string& s, std::string& error) {
            std::optional<ExecutorKind> k = parse_executor_kind(s, error);
            if (k) x.kind = *k;
            return k.has_value();
          },
          "What runs " + runs +
              ": interpreter (default), jit (hot map and apply sites, solver loops and "
              "other system statements compiled to native code with LLVM; the rest "
              "interpreted) or gpu (as jit, with the compiled maps and solver loops run on an "
              "NVIDIA GPU through the CUDA driver: an array is copied there only when the host "
              "changed it, and what a map or loop writes stays there until the host reads it "
              "(an output frame, the finite check, a print). "
              "--backend is another name of this option")
          ->type_name("interpreter|jit|gpu");
  t.threads = add_parsed(
                  sub, "--threads",
                  [&x](const std::string& s, std::string& error) {
                    std::optional<int> n = parse_threads(s, error);
                    if (n) x.threads = *n;
                    return n.has_value();
                  },
                  "jit: threads that run the compiled maps and solver loops, from 1 to " +
                      std::to_string(kMaxThreads) +
                      ", or all (or 0): every core this process may use (default: every core, " +
                      std::to_string(default_threads()) +
                      " here); results are the same for every count. The interpreter, and what "
                      "the JIT leaves interpreted, runs on one thread whatever N")
                  ->type_name("N|all");
  add_parsed(
      sub, "--jit-threshold",
      [&x](const std::string& s, std::string& error) {
        std::optional<long> n = parse_jit_threshold(s, error);
        if (n) x.threshold = *n;
        return n.has_value();
      },
      "jit: executions of a site before it is compiled (0: at once; default 2); a map over "
      "4096 elements or more and a while loop compile at their first execution regardless")
      ->type_name("N");
  t.cache = add_parsed(
                sub, "--jit-cache",
                [&x](const std::string& s, std::string& error) {
                  std::optional<std::string> c = parse_jit_cache(s, error);
                  if (c) x.jit_cache = *c;
                  return c.has_value();
                },
                "jit: where compiled kernels are kept between runs: off, or a folder (default: " +
                    std::string(x.jit_cache == "off" ? "off" : "the user's cache folder") + ")")
                ->type_name("off|DIR");
  add_parsed(
      sub, "--gpu-arch",
      [&x](const std::string& s, std::string& error) {
        std::optional<std::string> a = parse_gpu_arch(s, error);
        if (a) x.gpu_arch = *a;
        return a.has_value();
      },
      "gpu and --check-ptx: the GPU architecture kernels are compiled for, sm_XX (default "
      "sm_90, the H100's and H200's)")
      ->type_name("sm_XX");
  sub.add_flag("--jit-stats", *t.stats,
               "jit: print each trace (site, key, compile ms, calls, ms spent, or why it ran "
               "interpreted) " +
                   stats_when + "; needs --executor jit or gpu");
  sub.add_flag("--check-jit", x.check,
               "jit: run every compiled call interpreted as well, on the same inputs, and stop at "
               "the first result, field or variable that differs (bit for bit), naming it; needs "
               "--executor jit or gpu");
  sub.add_flag("--check-ptx", x.check_ptx,
               "Compile every trace the run compiles for the CPU for the GPU as well (PTX for "
               "sm_90, through LLVM's NVPTX back end) and assemble it with the CUDA toolkit's "
               "ptxas ($SIMIT_PTXAS, else ptxas on PATH, else /usr/local/cuda/bin/ptxas; no GPU "
               "needed); stop at the first PTX ptxas rejects, naming the trace. At the end, on "
               "stderr: how many traces were assembled and which were not compiled for the GPU, "
               "and why. Traces are compiled under --executor jit");
}

// --jit-stats and --check-jit say something about the JIT only: without it they would do
// nothing, silently. "" or the usage error. A scene's own `executor` key may choose the JIT
// when the command line does not: Scene::open checks those.
std::string jit_options_misused(const ExecutorFlags& t, bool scene) {
  if (compiles(t.choice->kind) || (scene && t.kind->count() == 0)) return "";
  if (t.choice->check) return "--check-jit needs --executor jit";
  if (*t.stats) return "--jit-stats needs --executor jit";
  return "";
}

void add_check(CLI::App& app, Commands& c) {
  c.check = app.add_subcommand("check", "Parse and type-check Simit programs");
  c.check->add_option("FILE", c.check_options.files, "Simit source files (.sim)")
      ->required()
      ->type_name("");
  c.check
      ->add_option("--dump", c.check_options.dumps,
                   "Also print a tree to stdout: 'ast' (the parse tree, when the file parses) "
                   "or 'typed' (the checked tree, when the file checks clean); "
                   "'ast,typed' prints both")
      ->type_name("KIND")
      ->delimiter(',')
      ->check(CLI::IsMember({"ast", "typed"}));
  c.check->footer(
      "Diagnostics go to stderr as file:line:col: error: message, with the source line and a "
      "caret.\nExit status: 0 when every file is clean, 1 when any file has errors or cannot "
      "be read, 2 on a usage error.\n");
}

void add_partition(CLI::App& app, Commands& c) {
  c.partition = app.add_subcommand(
      "partition", "Cut a mesh's vertex graph into parts, as the distributed executor will");
  c.partition->add_option("MESH", c.partition_options.mesh, "A mesh file (.node/.ele, .msh, .obj)")
      ->required()
      ->type_name("");
  c.partition
      ->add_option("--parts", c.partition_options.parts,
                   "How many parts, e.g. 2,4,8 (one line each; default 2)")
      ->type_name("K,...")
      ->delimiter(',')
      ->check(CLI::Range(1, 1 << 20));
  c.partition->add_flag("--csv", c.partition_options.csv,
                        "Print comma-separated lines instead of the table");
  c.partition
      ->add_option("--reorder", c.partition_options.reorder,
                   "Renumber the vertices first, as a scene's `reorder` key does (default: rcm, "
                   "a scene's default)")
      ->type_name("rcm|hilbert|off")
      ->check(CLI::IsMember({"rcm", "hilbert", "off"}));
  c.partition->footer(
      "Every two vertices of an element (tet, triangle, edge) are adjacent. As in a "
      "distributed run, each part owns whole chunks of 256 consecutive vertices (after the "
      "renumbering), the chunks of the blocked sums: METIS's k-way partitioner cuts the graph "
      "between chunks, with a fixed seed (the same parts on every run), balancing the parts' "
      "vertices and the elements they own. An element "
      "belongs to the part of its lowest-numbered vertex; a part's ghosts are the vertices its "
      "elements reach that other parts own, its neighbours the parts that own them. Columns: "
      "cut edges (and their share of the graph's), the largest part's vertices and elements "
      "over the mean, ghosts in all parts and in the part with most, the most neighbours of "
      "a part, and the partitioner's time.\nExit status: 0, 1 when the mesh does not read or "
      "the parts do not fit it, 2 on a usage error.\n");
}

void add_test(CLI::App& app, Commands& c) {
  c.test = app.add_subcommand("test", "Run .sim test files (the inline test format)");
  c.test->add_option("PATH", c.test_paths, "Test files, or folders searched for *.sim files")
      ->required()
      ->type_name("");
  c.test->add_flag("-v,--verbose", c.test_options.verbose,
                   "List every section with PASS, SKIP or FAIL (default: failures only)");
  c.test->add_flag("--float32", c.test_options.float32, "Run programs with 32-bit floats");
  c.test->add_flag("--check-finite", c.test_options.check_finite,
                   "Stop a run with a run-time error at the first NaN or infinity it produces");
  add_executor_options(*c.test, c.test_executor, "the sections",
                       "under each section listed (failures; every section with -v) that made one, "
                       "and before the last line how many traces all sections made, compiled and "
                       "interpreted, with the reasons counted");
  c.test->footer(
      "Each section is compiled on its own. Sections in a folder named 'illegal', or with a "
      "'%@ error' directive, must be rejected; the others must compile, and their %! tests "
      "run in the interpreter, as do their graph directives (%@ set, %@ run, %@ expect, ...); "
      "with --executor jit, hot maps and runs of system statements (solver loops) run compiled.\n"
      "With --check-jit a section whose compiled code differs from the interpreter fails with "
      "the '--check-jit: ...' message naming the difference.\n"
      "Ends with 'N passed, N failed[, N skipped]'. Exit status: 0 when nothing failed, 1 "
      "otherwise, 2 on a usage error.\n");
}

// A whole number of frames. CLI::NonNegativeNumber printed its bound, the largest double,
// in 309 digits.
CLI::Validator frame_count() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        int n = 0;
        auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), n);
        if (ec == std::errc() && end == s.data() + s.size() && n >= 0) return "";
        return "expected a whole number of frames from 0 to " +
               std::to_string(std::numeric_limits<int>::max()) + ", got '" + s + "'";
      },
      "FRAMES");
}

void add_run(CLI::App& app, Commands& c) {
  RunOptions& o = c.run_options;
  SceneOptions& so = c.scene_options;
  c.run = app.add_subcommand(
      "run",
      "Run a scene (FILE.toml), or an exported function that needs no sets (FILE.sim --call)");
  c.run->add_option("FILE", o.file, "A scene (.toml) or a Simit source file (.sim)")->required();
  c.run->add_option("--call", o.func, "Name of the exported function (.sim files; required there)");
  // The arguments are taken raw (CLI11 would split `[1, 2]` at its comma).
  c.run->allow_extras();
  c.run->add_flag("--float32", o.float32, "Run with 32-bit floats");
  c.run->add_flag("--check-finite", o.check_finite,
                  "Stop with a run-time error at the first NaN or infinity produced");
  c.run->add_flag("--no-finite-check", c.no_finite_check,
                  "Scenes: let NaN and infinity through (by default the run stops at the first "
                  "one in the sets' float fields or step's results, checked after init and after "
                  "every frame; the frames before it stay written)");
  add_executor_options(*c.run, c.run_executor, "the program",
                       "after the run, also after the error message when it stops on a run-time "
                       "error, a NaN or infinity, or Ctrl-C (which then stops the run at its next "
                       "statement; a second Ctrl-C ends it at once)");
  c.run
      ->add_option_function<std::vector<std::string>>(
          "--dump",
          [&o](const std::vector<std::string>& kinds) {
            std::string error;
            for (const std::string& k : kinds)
              if (!parse_dump_kind(k, o.executor, error))
                throw CLI::ValidationError("--dump", error);
          },
          "jit: print each compiled trace: loop-ir (as compiled), passes (as traced and after each "
          "lowering pass), llvm, ptx (its PTX for the GPU, or why it has none)")
      ->type_name("KIND")
      ->delimiter(',');
  c.run->add_option("--frames", so.frames, "Scenes: run this many frames instead of the scene's")
      ->check(frame_count());
  c.run->add_option("--output", so.output_dir, "Scenes: write the output into this folder");
  c.run->add_option("--final-csv", so.final_csv,
                    "Scenes: write the last frame's positions to this CSV file (x,y,z lines)");
  c.run->add_flag("--distributed", c.distributed,
                  "Scenes, under mpirun -np K: each rank runs the program over its part of the "
                  "sets (cut by METIS; rank 0 writes the output); the interpreter only, so far");
  c.run->add_option("--png", so.png,
                    "Scenes: write a quick-look picture of the last frame to this PNG file "
                    "(instead of [output] png)");
  c.run->footer(
      "A .toml FILE is a scene (see README.md, 'Scenes'): its sets are built from mesh files, "
      "its init procedure runs once and its step procedure once per frame, and the output is a "
      "ParaView series (NAME.pvd + one .vtu per frame), each frame written on a thread of its "
      "own while the next computes where the run leaves a core free ([output] background "
      "decides otherwise).\n"
      "A .sim FILE needs --call NAME. ARGS: one literal per parameter after the file, e.g. 2 "
      "-1.5 true \"text\" <1.0,-1.0> \"[1.0, 2.0]'\" (a column vector) \"[1, 2; 3, 4]\".\n"
      "Prints what the program prints, then one 'name = value' line per result.\nExit status: "
      "0 on success, 1 when the file does not compile, the scene or the arguments do not fit or "
      "the run stops with a run-time error, 2 on a usage error.\n");
}

#ifdef SIMIT_HAVE_REPL
void add_repl(CLI::App& app, Commands& c) {
  c.repl = app.add_subcommand("repl", "Start the interactive REPL (also: simit with no command)");
  c.repl->add_option("FILE", c.repl_file,
                     "A Simit source file (.sim) to load, or a scene (.toml) to bind, first");
  c.repl->footer(
      "On a terminal: line editing, history in ~/.simit_history, tab completion of commands, "
      "names and set.field. Otherwise reads lines from stdin with no prompt. Ctrl-C stops a "
      "running computation; Ctrl-D or :quit leaves. :help lists the commands.\n");
}

void add_debug(CLI::App& app, Commands& c) {
  DebugOptions& o = c.debug_options;
  c.debug =
      app.add_subcommand("debug", "Step-debug a scene (FILE.toml) or a Simit program (FILE.sim)");
  c.debug->add_option("FILE", o.file, "A scene (.toml) or a Simit source file (.sim)")->required();
  c.debug->add_flag("--echo", o.echo,
                    "Print each command read after the prompt (for transcripts; without a terminal "
                    "no prompt is shown otherwise)");
  c.debug->add_flag("--float32", o.float32, "Run with 32-bit floats");
  c.debug->footer(
      "Reads gdb-style commands from stdin ('help' lists them): break FILE:LINE | LINE | FUNC "
      "[if COND], tbreak, break on nan, watch SET.FIELD[i], delete, info breakpoints|locals|"
      "display, run, continue, next, step, finish, kill, print, display, undisplay, backtrace, "
      "up, down, frame, list, quit. In a condition an element compared with an int compares its "
      "index: break tet_force if t == 17.\n"
      "A scene runs with 'run [FRAMES]' (its init, then FRAMES frames, default the scene's), "
      "writing no output files; a .sim file with 'run FUNC ARGS...' (an exported function, "
      "literal arguments as for simit run --call). Ctrl-C pauses a run at its next statement and "
      "reads commands there (continue, kill, ...), as gdb does.\n"
      "Exit status: 0, or 1 when the program does not compile.\n");
}
#endif

#ifdef SIMIT_HAVE_DAP
void add_dap(CLI::App& app, Commands& c) {
  c.dap = app.add_subcommand(
      "dap", "Serve the step debugger over the Debug Adapter Protocol on stdin/stdout (editors)");
  c.dap->footer(
      "An editor starts it (editors/vscode: the 'simit' debug type) and sends the launch "
      "arguments: program (a scene .toml or a .sim file), cwd, function and args (a .sim), "
      "frames, stopOnEntry, float32. Line, conditional, hit-count and function breakpoints, "
      "the exception filter 'nan' (break on nan), data breakpoints SET.FIELD[i] (watch), "
      "stepping, pause, frames with the mapped element, variables and evaluate (the debugger's "
      "expressions). Exit status 0 when the session ends.\n");
}
#endif

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

int usage_error(const CLI::App& app, const std::string& message, std::ostream& err) {
  err << "simit: error: " << message << "\n\n" << app.help();
  return kUsageError;
}

// CLI11 would report an unknown subcommand as a stray argument; name it plainly instead.
bool names_unknown_command(const CLI::App& app, int argc, const char* const* argv) {
  if (argc < 2 || argv[1][0] == '-') return false;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    if (sub->get_name() == argv[1]) return false;
  return true;
}

// What `simit run SCENE.toml` hands to the scene: the options given, and which of them were
// given (those win over the scene file's keys).
SceneOptions scene_options(const Commands& c) {
  SceneOptions so = c.scene_options;
  so.file = c.run_options.file;
  so.float32 = c.run_options.float32;
  so.check_finite = c.run_options.check_finite;
  so.executor = c.run_options.executor;
  so.executor_given = c.run_executor.kind->count() > 0;
  so.threads_given = c.run_executor.threads->count() > 0;
  so.jit_cache_given = c.run_executor.cache->count() > 0;
  so.jit_stats = c.run_options.jit_stats;
  so.finite_check = !c.no_finite_check;
  return so;
}

void add_commands(CLI::App& app, Commands& c) {
  app.set_version_flag("--version", "simit " SIMIT_VERSION);
  add_check(app, c);
  add_test(app, c);
  add_run(app, c);
  add_partition(app, c);
#ifdef SIMIT_HAVE_REPL
  app.require_subcommand(0, 1);
  add_repl(app, c);
  add_debug(app, c);
  app.footer("With no command, simit starts the REPL.\n");
#endif
#ifdef SIMIT_HAVE_DAP
  add_dap(app, c);
#endif
#ifndef SIMIT_HAVE_REPL
  app.require_subcommand(1);
#endif
}

}  // namespace

namespace {

// The command line parsed into `c` without running anything (for the tests of the options).
bool parse_only(CLI::App& app, Commands& c, int argc, const char* const* argv, std::ostream& err) {
  add_commands(app, c);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    err << "simit: error: " << e.what() << "\n";
    return false;
  }
  return true;
}

}  // namespace

std::optional<ExecutorChoice> parse_executor_choice(int argc, const char* const* argv,
                                                    std::ostream& err) {
  CLI::App app("Simit: a language for physical simulation on hypergraphs.", "simit");
  Commands c;
  if (!parse_only(app, c, argc, argv, err)) return std::nullopt;
  if (c.run->parsed()) return c.run_options.executor;
  if (c.test->parsed()) return c.test_options.executor;
  err << "simit: error: neither run nor test\n";
  return std::nullopt;
}

std::optional<SceneOptions> parse_scene_options(int argc, const char* const* argv,
                                                std::ostream& err) {
  CLI::App app("Simit: a language for physical simulation on hypergraphs.", "simit");
  Commands c;
  if (!parse_only(app, c, argc, argv, err)) return std::nullopt;
  if (c.run->parsed() && ends_with(c.run_options.file, ".toml")) return scene_options(c);
  err << "simit: error: not a scene run\n";
  return std::nullopt;
}

int run_cli(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app("Simit: a language for physical simulation on hypergraphs.", "simit");
  Commands c;
  add_commands(app, c);
  if (names_unknown_command(app, argc, argv))
    return usage_error(app, std::string("unknown command '") + argv[1] + "'", err);
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    out << (e.get_name() == "CallForVersion" ? std::string(e.what()) + "\n" : app.help());
    return 0;
  } catch (const CLI::ParseError& e) {
    return usage_error(app, e.what(), err);
  }
#ifdef SIMIT_HAVE_DAP
  if (c.dap->parsed()) return run_dap(0, 1, err);
#endif
#ifdef SIMIT_HAVE_REPL
  if (c.debug->parsed()) return run_debug(c.debug_options, std::cin, out, err);
  if (c.repl->parsed()) return repl::run_repl(c.repl_file);
  if (app.get_subcommands().empty()) return repl::run_repl("");
#endif
  if (c.check->parsed()) return run_check(c.check_options, out, err);
  if (c.partition->parsed()) {
    if (c.partition_options.parts.empty()) c.partition_options.parts = {2};
    return run_partition(c.partition_options, out, err);
  }
  const bool scene = c.run->parsed() && ends_with(c.run_options.file, ".toml");
  for (const auto& [sub, flags] :
       {std::pair{c.run, &c.run_executor}, std::pair{c.test, &c.test_executor}})
    if (sub->parsed())
      if (std::string bad = jit_options_misused(*flags, scene); !bad.empty())
        return usage_error(app, sub->get_name() + ": " + bad, err);
  // --check-ptx: what was checked, on stderr after the run (a choice this build cannot run
  // has already been reported).
  const ExecutorChoice& choice = c.run->parsed() ? c.run_options.executor : c.test_options.executor;
  auto checked = [&](int status) {
    if (choice.check_ptx && executor_unavailable(choice).empty()) {
      out.flush();
      err << check_ptx_summary() << "\n";
    }
    return status;
  };
  if (c.run->parsed()) {
    if (ends_with(c.run_options.file, ".toml")) {
      if (!c.run_options.func.empty() || !c.run->remaining().empty())
        return usage_error(app, "a scene (.toml) takes no --call and no arguments", err);
      SceneOptions so = scene_options(c);
      so.progress_line = &out == &std::cout && isatty(fileno(stdout));
      scene::remove_temporaries_on_signals();  // a killed run leaves complete files only
      if (c.distributed) return checked(run_distributed_scene(so, out, err));
      return checked(run_scene(so, out, err));
    }
    if (c.distributed) return usage_error(app, "run: --distributed runs scenes (.toml) only", err);
    if (c.run_options.func.empty())
      return usage_error(app, "run: a .sim file needs --call NAME (or give a .toml scene)", err);
    c.run_options.args = c.run->remaining();
    return checked(run_function(c.run_options, out, err));
  }
  return checked(run_test_command(c.test_paths, c.test_options, out, err));
}

}  // namespace simit::tools
