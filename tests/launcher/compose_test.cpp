// compose.yaml reading: interpolation forms, command splitting, environment forms,
// replicas, start order, key-path errors, x-tessera extension.
#include "master/launcher/compose.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

namespace tessera::launcher {
namespace {

VariableLookup fixedEnv(std::map<std::string, std::string> vars) {
  return [vars](const std::string& k) -> std::optional<std::string> {
    auto it = vars.find(k);
    return it == vars.end() ? std::nullopt : std::optional<std::string>(it->second);
  };
}

std::string interp(const std::string& text, std::vector<std::string>* warnings = nullptr) {
  return interpolate(text, fixedEnv({{"SET", "value"}, {"EMPTY", ""}}), warnings, "x");
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ComposeError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Interpolate, EveryForm) {
  EXPECT_EQ(interp("$SET"), "value");
  EXPECT_EQ(interp("${SET}"), "value");
  EXPECT_EQ(interp("a${SET}b$SET.c"), "avaluebvalue.c");
  EXPECT_EQ(interp("${UNSET:-d}"), "d");
  EXPECT_EQ(interp("${EMPTY:-d}"), "d");   // ':' treats empty as unset
  EXPECT_EQ(interp("${EMPTY-d}"), "");     // without ':' only unset counts
  EXPECT_EQ(interp("${UNSET-d}"), "d");
  EXPECT_EQ(interp("${SET:-d}"), "value");
  EXPECT_EQ(interp("${SET:+alt}"), "alt");
  EXPECT_EQ(interp("${EMPTY:+alt}"), "");
  EXPECT_EQ(interp("${EMPTY+alt}"), "alt");
  EXPECT_EQ(interp("${UNSET+alt}"), "");
  EXPECT_EQ(interp("${UNSET:-a b:c}"), "a b:c");
  EXPECT_EQ(interp("${EMPTY?err}"), "");
  EXPECT_EQ(interp("${SET:?err}"), "value");
}

TEST(Interpolate, DollarEscape) {
  EXPECT_EQ(interp("$$SET"), "$SET");
  EXPECT_EQ(interp("kill $$$$"), "kill $$");
  EXPECT_EQ(interp("a$${SET}"), "a${SET}");
  EXPECT_EQ(interp("${UNSET:-$$}"), "$");
}

TEST(Interpolate, NestedDefaults) {
  EXPECT_EQ(interp("${UNSET:-${SET}/x}"), "value/x");
  EXPECT_EQ(interp("${UNSET:-${UNSET2:-deep}}"), "deep");
  EXPECT_EQ(interp("${SET:+[${SET}]}"), "[value]");
  // A default that is not used is not evaluated, so its :? cannot fire.
  EXPECT_EQ(interp("${SET:-${UNSET:?never}}"), "value");
}

TEST(Interpolate, MissingVariableIsEmptyWithWarning) {
  std::vector<std::string> warnings;
  EXPECT_EQ(interp("<$UNSET>", &warnings), "<>");
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("\"UNSET\" variable is not set"), std::string::npos) << warnings[0];
  EXPECT_EQ(interp("${EMPTY}", &warnings), "");  // set but empty: no warning
  EXPECT_EQ(warnings.size(), 1u);
}

TEST(Interpolate, RequiredErrors) {
  EXPECT_EQ(errorOf([] { interp("${UNSET:?need a scene}"); }),
            "x: required variable UNSET is missing a value: need a scene");
  EXPECT_EQ(errorOf([] { interp("${EMPTY:?empty too}"); }),
            "x: required variable EMPTY is missing a value: empty too");
  EXPECT_EQ(errorOf([] { interp("${UNSET?}"); }), "x: required variable UNSET is missing a value");
  EXPECT_EQ(errorOf([] { interp("${UNSET:?for ${SET}}"); }),
            "x: required variable UNSET is missing a value: for value");
}

TEST(Interpolate, InvalidFormats) {
  for (const char* bad : {"$", "a $ b", "${", "${SET", "${1X}", "${}", "${SET:}", "${SET*x}"}) {
    EXPECT_NE(errorOf([bad] { interp(bad); }).find("invalid interpolation format"), std::string::npos) << bad;
  }
}

TEST(SplitCommandLine, QuotesAndEscapes) {
  const auto w = splitCommandLine(R"(  a 'b  c' "d \"e\" \n" f\ g '' x'y'"z" )", "cmd");
  const std::vector<std::string> expect = {"a", "b  c", R"(d "e" \n)", "f g", "", "xyz"};
  EXPECT_EQ(w, expect);
  EXPECT_TRUE(splitCommandLine("   ", "cmd").empty());
  EXPECT_NE(errorOf([] { splitCommandLine("sh -c 'oops", "cmd"); }).find("unterminated '"), std::string::npos);
}

TEST(DotEnv, Forms) {
  const auto v = parseDotEnv("# comment\n\nA=1\nexport B = two words # note\nC=\"q # kept\\n\"\nD='lit $x'\nE=\n",
                             ".env");
  EXPECT_EQ(v.at("A"), "1");
  EXPECT_EQ(v.at("B"), "two words");
  EXPECT_EQ(v.at("C"), "q # kept\n");
  EXPECT_EQ(v.at("D"), "lit $x");
  EXPECT_EQ(v.at("E"), "");
  EXPECT_EQ(errorOf([] { parseDotEnv("A=1\nnot a pair\n", ".env"); }),
            ".env:2: expected KEY=VALUE, got \"not a pair\"");
}

ComposeProject parse(const std::string& yaml, std::map<std::string, std::string> env = {},
                     std::map<std::string, std::string> overrides = {},
                     const std::filesystem::path& dir = "/nonexistent-dir") {
  ComposeOptions options;
  options.process_env = fixedEnv(std::move(env));
  options.overrides = std::move(overrides);
  return parseCompose(yaml, dir, options, "compose.yaml");
}

TEST(Compose, EnvironmentMapAndListForms) {
  const auto p = parse(R"(
services:
  a:
    command: run
    environment:
      X: "1"
      Y: "${SCENE:-builtin}"
      PASS:
      GONE:
  b:
    command: run
    environment: ["X=2", "Y=a=b", "PASS", "GONE", "Z=${SCENE}"]
)", {{"PASS", "through"}, {"SCENE", "s.yaml"}});
  const std::map<std::string, std::string> a = {{"X", "1"}, {"Y", "s.yaml"}, {"PASS", "through"}};
  const std::map<std::string, std::string> b = {{"X", "2"}, {"Y", "a=b"}, {"PASS", "through"}, {"Z", "s.yaml"}};
  EXPECT_EQ(p.find("a")->environment, a);
  EXPECT_EQ(p.find("b")->environment, b);
}

TEST(Compose, CommandFormsEntrypointAndReplicas) {
  const auto p = parse(R"(
version: "3.9"
name: farm
x-anchors: &cmd ["tessera-renderer", "--scene", "${SCENE:-builtin}"]
networks: {farm: {}}
volumes: {out: {}}
services:
  renderer:
    image: tessera:latest
    build: .
    ports: ["5555:5555"]
    restart: unless-stopped
    healthcheck: {test: ["CMD", "true"]}
    x-note: anything
    command: *cmd
    deploy: {replicas: "${N:-2}", resources: {limits: {cpus: "1"}}}
  master:
    entrypoint: /usr/local/bin/tessera-master
    command: --out 'my out/'
)", {}, {{"N", "4"}});
  EXPECT_EQ(p.name, "farm");
  const auto* r = p.find("renderer");
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->replicas, 4);
  EXPECT_EQ(r->argv, (std::vector<std::string>{"tessera-renderer", "--scene", "builtin"}));
  const auto* m = p.find("master");
  EXPECT_EQ(m->replicas, 1);
  EXPECT_EQ(m->argv, (std::vector<std::string>{"/usr/local/bin/tessera-master", "--out", "my out/"}));
}

TEST(Compose, DependsOnOrdersStart) {
  const auto p = parse(R"(
services:
  display: {command: d, depends_on: {compositor: {condition: service_started}}}
  compositor: {command: c, depends_on: [master, renderer]}
  renderer: {command: r, depends_on: [master]}
  master: {command: m}
)");
  std::vector<std::string> order;
  for (const auto& s : p.services) order.push_back(s.name);
  EXPECT_EQ(order, (std::vector<std::string>{"master", "renderer", "compositor", "display"}));
  EXPECT_NE(errorOf([] { parse("services: {a: {command: x, depends_on: [b]}, b: {command: y, depends_on: [a]}}"); })
                .find("depends_on cycle among: a, b"),
            std::string::npos);
  EXPECT_EQ(errorOf([] { parse("services: {a: {command: x, depends_on: [nope]}}"); }),
            "compose.yaml: services.a.depends_on: unknown or disabled service \"nope\"");
}

TEST(Compose, UnknownKeysNameTheirPath) {
  EXPECT_EQ(errorOf([] { parse("servics: {}\nservices: {a: {command: x}}"); }), "compose.yaml: servics: unknown key");
  EXPECT_EQ(errorOf([] { parse("services: {renderer: {comand: x}}"); }),
            "compose.yaml: services.renderer.comand: unknown key");
  EXPECT_EQ(errorOf([] { parse("services: {renderer: {command: x, deploy: {replica: 2}}}"); }),
            "compose.yaml: services.renderer.deploy.replica: unknown key");
  EXPECT_EQ(errorOf([] { parse("services: {r: {command: x, deploy: {replicas: two}}}"); }),
            "compose.yaml: services.r.deploy.replicas: expected an integer, got \"two\"");
  EXPECT_EQ(errorOf([] { parse("services: {r: {command: x, x-tessera: {local: y}}}"); }),
            "compose.yaml: services.r.x-tessera.local: unknown key (known: local_command, local_environment, "
            "exit_leader)");
  EXPECT_NE(errorOf([] { parse("services: {r: {image: tessera}}"); }).find("services.r: no command"),
            std::string::npos);
  EXPECT_NE(errorOf([] { parse("services: {r: {command: '${SCENE:?set TESSERA_SCENE}'}}"); })
                .find("services.r.command: required variable SCENE is missing a value: set TESSERA_SCENE"),
            std::string::npos);
}

TEST(Compose, TesseraExtension) {
  const auto p = parse(R"(
services:
  master:
    entrypoint: ["/usr/local/bin/tessera-master"]
    command: ["--in-flight", "3"]
    environment: {TESSERA_ENDPOINTS: "tcp://master:5555", KEEP: "1"}
    x-tessera:
      local_command: "tessera-master --in-flight 3 --log ${LOG:-info}"
      local_environment: ["TESSERA_ENDPOINTS=ipc://${DIR:-/tmp/farm}"]
  display: {command: show}
  viewer: {command: view, x-tessera: {exit_leader: true}}
  sink: {command: sink, x-tessera: {exit_leader: "false"}}
)");
  EXPECT_EQ(p.find("master")->argv,
            (std::vector<std::string>{"tessera-master", "--in-flight", "3", "--log", "info"}));
  const std::map<std::string, std::string> env = {{"TESSERA_ENDPOINTS", "ipc:///tmp/farm"}, {"KEEP", "1"}};
  EXPECT_EQ(p.find("master")->environment, env);
  EXPECT_FALSE(p.find("master")->exit_leader);
  EXPECT_TRUE(p.find("display")->exit_leader);  // by name
  EXPECT_TRUE(p.find("viewer")->exit_leader);   // by flag
  EXPECT_FALSE(p.find("sink")->exit_leader);
}

TEST(Compose, VariablePrecedenceAndDotEnv) {
  char tmpl[] = "/tmp/tessera-compose-XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const std::filesystem::path dir = tmpl;
  std::ofstream(dir / ".env") << "A=dotenv\nB=dotenv\nC=dotenv\n";
  std::ofstream(dir / "extra.env") << "E1=from-file\nE2=from-file\n";
  const std::string yaml = R"(
services:
  s:
    command: echo $A $B $C
    env_file: extra.env
    environment: {E2: own}
)";
  const auto p = parse(yaml, {{"B", "process"}, {"C", "process"}}, {{"C", "override"}}, dir);
  EXPECT_EQ(p.find("s")->argv, (std::vector<std::string>{"echo", "dotenv", "process", "override"}));
  const std::map<std::string, std::string> env = {{"E1", "from-file"}, {"E2", "own"}};
  EXPECT_EQ(p.find("s")->environment, env);
  EXPECT_EQ(p.directory, dir);
  std::filesystem::remove_all(dir);
}

TEST(Compose, ProfilesDisableServices) {
  const std::string yaml = "services: {a: {command: x}, debug: {command: y, profiles: [debug]}}";
  EXPECT_EQ(parse(yaml).services.size(), 1u);
  EXPECT_EQ(parse(yaml, {{"COMPOSE_PROFILES", "debug"}}).services.size(), 2u);
}

}  // namespace
}  // namespace tessera::launcher
