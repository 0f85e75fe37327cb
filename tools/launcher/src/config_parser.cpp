// Recursive-descent parser for the procman configuration subset.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "config_lexer.hpp"
#include "ivoa/launcher/config.hpp"

namespace ivoa::launcher {
namespace {

// Attributes real procman (or libbot's bot-procman) knows that have no
// meaning for a single-machine launcher: accepted with a warning.
const std::set<std::string> kIgnoredAttributes = {"nickname", "group", "command_id"};

class Parser {
 public:
  // "# @default" comments may stand anywhere: they are taken out of the
  // token stream first.
  Parser(const std::vector<Token>& tokens, std::string path) : path_(std::move(path)) {
    config_.path = path_;
    for (const Token& t : tokens) {
      if (t.kind == TokenKind::kDefault) variable_default(t);
      else tokens_.push_back(t);
    }
  }

  Config run() {
    while (peek().kind != TokenKind::kEnd) top_level_item();
    for (const auto& script : config_.scripts) flatten_script(config_, script.name);  // checks references
    return std::move(config_);
  }

 private:
  const Token& peek() const { return tokens_[pos_]; }
  const Token& take() { return tokens_[pos_ < tokens_.size() - 1 ? pos_++ : pos_]; }

  [[noreturn]] void fail(int line, const std::string& what) const {
    throw ConfigError(path_ + ":" + std::to_string(line) + ": " + what);
  }
  const Token& expect(TokenKind kind, const std::string& what) {
    if (peek().kind != kind) fail(peek().line, "expected " + what + ", found " + describe(peek()));
    return take();
  }
  bool accept_keyword(const std::string& word) {
    if (peek().kind != TokenKind::kIdentifier || peek().text != word) return false;
    take();
    return true;
  }
  std::string expect_name(const std::string& of_what) {
    const Token& t = expect(TokenKind::kString, "a quoted " + of_what + " name");
    if (t.text.empty()) fail(t.line, of_what + " name is empty");
    return t.text;
  }

  void top_level_item() {
    if (accept_keyword("group")) return group("");
    if (accept_keyword("cmd")) return command("");
    if (accept_keyword("script")) return script();
    fail(peek().line, "expected 'group', 'cmd' or 'script', found " + describe(peek()));
  }

  void variable_default(const Token& t) {
    const auto eq = t.text.find('=');
    std::string name = t.text.substr(0, eq);
    name.erase(name.find_last_not_of(" \t") + 1);
    const bool valid_name = !name.empty() && (std::isalpha(static_cast<unsigned char>(name[0])) || name[0] == '_') &&
                            std::all_of(name.begin(), name.end(),
                                        [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
    if (eq == std::string::npos || !valid_name) fail(t.line, "expected '# @default NAME = VALUE'");
    std::string value = t.text.substr(eq + 1);
    value.erase(0, value.find_first_not_of(" \t"));
    if (value.size() >= 2 && value.front() == '"' && value.back() == '"') value = value.substr(1, value.size() - 2);
    if (const auto it = config_.defaults.find(name); it != config_.defaults.end())
      fail(t.line, "default for " + name + " already given at line " + std::to_string(it->second.line));
    config_.defaults[name] = {value, t.line};
  }

  void group(const std::string& parent) {
    const int line = peek().line;
    const std::string name = expect_name("group");
    if (name.find('/') != std::string::npos) fail(line, "group name '" + name + "' contains '/' (nest groups instead)");
    const std::string path = parent.empty() ? name : parent + "/" + name;
    if (!config_.has_group(path)) config_.groups.push_back(path);
    expect(TokenKind::kLeftBrace, "'{' after group \"" + name + "\"");
    while (!accept(TokenKind::kRightBrace)) {
      if (accept_keyword("group")) group(path);
      else if (accept_keyword("cmd")) command(path);
      else fail(peek().line, "expected 'cmd', 'group' or '}' in group \"" + path + "\", found " + describe(peek()));
    }
  }

  bool accept(TokenKind kind) {
    if (peek().kind != kind) return false;
    take();
    return true;
  }

  void command(const std::string& group_path) {
    CommandSpec cmd;
    cmd.line = peek().line;
    cmd.name = expect_name("command");
    cmd.group = group_path;
    if (const CommandSpec* other = config_.find_command(cmd.name))
      fail(cmd.line, "command \"" + cmd.name + "\" already defined at line " + std::to_string(other->line));
    expect(TokenKind::kLeftBrace, "'{' after cmd \"" + cmd.name + "\"");
    std::set<std::string> seen;
    bool has_exec = false;
    while (!accept(TokenKind::kRightBrace)) {
      const Token& key = expect(TokenKind::kIdentifier, "an attribute name or '}' in cmd \"" + cmd.name + "\"");
      expect(TokenKind::kAssign, "'=' after '" + key.text + "'");
      const Token& value = take();
      if (value.kind != TokenKind::kString && value.kind != TokenKind::kNumber && value.kind != TokenKind::kIdentifier)
        fail(value.line, "expected a value for '" + key.text + "', found " + describe(value));
      expect(TokenKind::kSemicolon, "';' after the value of '" + key.text + "'");
      if (!seen.insert(key.text == "deputy" ? "host" : key.text).second)
        fail(key.line, "'" + key.text + "' given twice in cmd \"" + cmd.name + "\"");
      has_exec |= key.text == "exec";
      set_attribute(cmd, key, value);
    }
    if (!has_exec) fail(cmd.line, "cmd \"" + cmd.name + "\" has no exec");
    config_.commands.push_back(std::move(cmd));
  }

  void set_attribute(CommandSpec& cmd, const Token& key, const Token& value) {
    const std::string& k = key.text;
    if (k == "exec") {
      if (value.text.find_first_not_of(" \t\n") == std::string::npos) fail(value.line, "exec is empty");
      cmd.exec = value.text;
    } else if (k == "host" || k == "deputy") {
      cmd.host = value.text;
    } else if (k == "auto_respawn") {
      cmd.auto_respawn = parse_bool(value, k);
    } else if (k == "stop_signal") {
      const double s = parse_number(value, k);
      if (s != std::floor(s) || s < 1 || s > 64)
        fail(value.line, "stop_signal must be a signal number 1-64, got " + value.text);
      cmd.stop_signal = static_cast<int>(s);
    } else if (k == "stop_time_allowed") {
      cmd.stop_time_allowed_s = parse_number(value, k);
      if (cmd.stop_time_allowed_s < 0) fail(value.line, "stop_time_allowed must be >= 0 seconds");
    } else if (kIgnoredAttributes.count(k)) {
      config_.warnings.push_back(path_ + ":" + std::to_string(key.line) + ": attribute '" + k + "' ignored");
    } else {
      fail(key.line,
           "unknown attribute '" + k + "' (known: exec, host, deputy, auto_respawn, stop_signal, stop_time_allowed)");
    }
  }

  bool parse_bool(const Token& value, const std::string& key) const {
    if (value.text == "true" || value.text == "1") return true;
    if (value.text == "false" || value.text == "0") return false;
    fail(value.line, key + " must be \"true\" or \"false\", got " + describe(value));
  }

  double parse_number(const Token& value, const std::string& key) const {
    std::istringstream in(value.text);
    double x = 0;
    if (!(in >> x) || !in.eof()) fail(value.line, key + " must be a number, got " + describe(value));
    return x;
  }

  void script() {
    ScriptSpec s;
    s.line = peek().line;
    s.name = expect_name("script");
    if (const ScriptSpec* other = config_.find_script(s.name))
      fail(s.line, "script \"" + s.name + "\" already defined at line " + std::to_string(other->line));
    expect(TokenKind::kLeftBrace, "'{' after script \"" + s.name + "\"");
    while (!accept(TokenKind::kRightBrace)) s.steps.push_back(script_step());
    config_.scripts.push_back(std::move(s));
  }

  ScriptStep script_step() {
    ScriptStep step;
    step.line = peek().line;
    const Token& verb = expect(TokenKind::kIdentifier, "a script action (start, stop, restart, wait, run_script)");
    if (verb.text == "start" || verb.text == "stop" || verb.text == "restart") {
      step.action = verb.text == "start"  ? StepAction::kStart
                    : verb.text == "stop" ? StepAction::kStop
                                          : StepAction::kRestart;
      target(step);
      if (accept_keyword("wait")) step.wait_status = status_word();
    } else if (verb.text == "wait") {
      if (accept_keyword("ms")) {
        step.action = StepAction::kWaitMs;
        const Token& ms = expect(TokenKind::kNumber, "a number of milliseconds");
        step.wait_ms = parse_number(ms, "wait ms");
        if (step.wait_ms < 0) fail(ms.line, "wait ms must be >= 0");
      } else {
        step.action = StepAction::kWaitStatus;
        target(step);
        if (!accept_keyword("status"))
          fail(peek().line, "expected 'status' after the wait target, found " + describe(peek()));
        step.wait_status = status_word();
      }
    } else if (verb.text == "run_script") {
      step.action = StepAction::kRunScript;
      step.target = expect_name("script");
    } else {
      fail(verb.line, "unknown script action '" + verb.text + "' (start, stop, restart, wait, run_script)");
    }
    expect(TokenKind::kSemicolon, "';' after the script action");
    return step;
  }

  void target(ScriptStep& step) {
    if (accept_keyword("everything")) {
      step.target_kind = TargetKind::kEverything;
    } else if (accept_keyword("cmd")) {
      step.target_kind = TargetKind::kCommand;
      step.target = expect_name("command");
    } else if (accept_keyword("group")) {
      step.target_kind = TargetKind::kGroup;
      step.target = expect_name("group");
    } else {
      fail(peek().line, "expected 'cmd', 'group' or 'everything', found " + describe(peek()));
    }
  }

  std::string status_word() {
    const Token& t = expect(TokenKind::kString, "\"running\" or \"stopped\"");
    if (t.text != "running" && t.text != "stopped")
      fail(t.line, "status must be \"running\" or \"stopped\", got " + describe(t));
    return t.text;
  }

  std::vector<Token> tokens_;
  size_t pos_ = 0;
  std::string path_;
  Config config_;
};

std::string at(const Config& config, int line) { return config.path + ":" + std::to_string(line) + ": "; }

void flatten_into(const Config& config, const ScriptSpec& script, std::vector<std::string>& stack,
                  std::vector<ScriptStep>& out) {
  stack.push_back(script.name);
  for (const auto& step : script.steps) {
    if (step.action == StepAction::kRunScript) {
      const ScriptSpec* inner = config.find_script(step.target);
      if (!inner) throw ConfigError(at(config, step.line) + "no script \"" + step.target + "\"");
      if (std::find(stack.begin(), stack.end(), step.target) != stack.end())
        throw ConfigError(at(config, step.line) + "script \"" + step.target + "\" runs itself");
      flatten_into(config, *inner, stack, out);
      continue;
    }
    if (step.target_kind == TargetKind::kCommand && step.action != StepAction::kWaitMs &&
        !config.find_command(step.target))
      throw ConfigError(at(config, step.line) + "no cmd \"" + step.target + "\"");
    if (step.target_kind == TargetKind::kGroup && step.action != StepAction::kWaitMs && !config.has_group(step.target))
      throw ConfigError(at(config, step.line) + "no group \"" + step.target + "\"");
    out.push_back(step);
  }
  stack.pop_back();
}

}  // namespace

const CommandSpec* Config::find_command(const std::string& name) const {
  for (const auto& c : commands)
    if (c.name == name) return &c;
  return nullptr;
}

const ScriptSpec* Config::find_script(const std::string& name) const {
  for (const auto& s : scripts)
    if (s.name == name) return &s;
  return nullptr;
}

bool Config::has_group(const std::string& path) const {
  return std::find(groups.begin(), groups.end(), path) != groups.end();
}

bool in_group(const CommandSpec& command, const std::string& group) {
  return command.group == group || command.group.rfind(group + "/", 0) == 0;
}

Config parse_config(const std::string& text, const std::string& path) {
  return Parser(tokenize(text, path), path).run();
}

Config load_config(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot read the configuration file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_config(text.str(), path);
}

std::vector<ScriptStep> flatten_script(const Config& config, const std::string& name) {
  const ScriptSpec* script = config.find_script(name);
  if (!script) throw ConfigError(config.path + ": no script \"" + name + "\"");
  std::vector<std::string> stack;
  std::vector<ScriptStep> out;
  flatten_into(config, *script, stack, out);
  return out;
}

}  // namespace ivoa::launcher
