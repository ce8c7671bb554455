// Text-level pieces of the Compose reader: variable interpolation, shell-like word
// splitting, .env parsing and quoting for display. See compose.h.
#include <cctype>

#include "master/launcher/compose.h"

namespace tessera::launcher {
namespace {

bool isNameStart(char c) { return c == '_' || std::isalpha(static_cast<unsigned char>(c)); }
bool isNameChar(char c) { return c == '_' || std::isalnum(static_cast<unsigned char>(c)); }

[[noreturn]] void invalid(const std::string& where, std::string_view text, const std::string& why) {
  throw ComposeError(where + ": invalid interpolation format in \"" + std::string(text) + "\": " +
                     why);
}

// Index of the '}' that closes a "${" whose body starts at `pos`; nested ${...} inside a
// default value are skipped over as a whole, and $$ never opens anything.
size_t findClose(std::string_view s, size_t pos, const std::string& where) {
  int depth = 1;
  for (size_t i = pos; i < s.size(); ++i) {
    if (s[i] == '$' && i + 1 < s.size() && (s[i + 1] == '$' || s[i + 1] == '{')) {
      if (s[i + 1] == '{') ++depth;
      ++i;
    } else if (s[i] == '}' && --depth == 0) {
      return i;
    }
  }
  invalid(where, s, "missing '}'");
}

std::string expandBraced(std::string_view body, std::string_view whole, const VariableLookup& lookup,
                         std::vector<std::string>* warnings, const std::string& where) {
  size_t n = 0;
  if (body.empty() || !isNameStart(body[0])) invalid(where, whole, "expected a variable name after ${");
  while (n < body.size() && isNameChar(body[n])) ++n;
  const std::string name(body.substr(0, n));
  std::string_view rest = body.substr(n);
  const std::optional<std::string> value = lookup(name);
  if (rest.empty()) {
    if (value) return *value;
    if (warnings) {
      warnings->push_back(where + ": the \"" + name +
                          "\" variable is not set; defaulting to a blank string");
    }
    return {};
  }
  const bool colon = rest[0] == ':';
  if (colon) rest.remove_prefix(1);
  if (rest.empty()) invalid(where, whole, "expected one of - ? + after ':'");
  const char op = rest[0];
  const std::string_view arg = rest.substr(1);
  // With ':' an empty value counts as unset, as in POSIX sh and Compose.
  const bool set = value.has_value() && (!colon || !value->empty());
  switch (op) {
    case '-':
      return set ? *value : interpolate(arg, lookup, warnings, where);
    case '+':
      return set ? interpolate(arg, lookup, warnings, where) : std::string();
    case '?':
      if (set) return *value;
      {
        const std::string message = interpolate(arg, lookup, warnings, where);
        throw ComposeError(where + ": required variable " + name + " is missing a value" +
                           (message.empty() ? std::string() : ": " + message));
      }
    default:
      invalid(where, whole, std::string("unknown operator '") + op + "' after the variable name");
  }
}

std::string trim(std::string_view s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return std::string(s.substr(b, e - b));
}

}  // namespace

std::string interpolate(std::string_view text, const VariableLookup& lookup,
                        std::vector<std::string>* warnings, const std::string& where) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size();) {
    if (text[i] != '$') {
      out += text[i++];
      continue;
    }
    if (i + 1 >= text.size()) invalid(where, text, "a lone '$' at the end (write $$ for a literal $)");
    const char next = text[i + 1];
    if (next == '$') {
      out += '$';
      i += 2;
    } else if (next == '{') {
      const size_t close = findClose(text, i + 2, where);
      out += expandBraced(text.substr(i + 2, close - i - 2), text, lookup, warnings, where);
      i = close + 1;
    } else if (isNameStart(next)) {
      size_t j = i + 1;
      while (j < text.size() && isNameChar(text[j])) ++j;
      out += expandBraced(text.substr(i + 1, j - i - 1), text, lookup, warnings, where);
      i = j;
    } else {
      invalid(where, text, std::string("'$' followed by '") + next + "' (write $$ for a literal $)");
    }
  }
  return out;
}

std::vector<std::string> splitCommandLine(std::string_view s, const std::string& where) {
  std::vector<std::string> words;
  std::string cur;
  bool have = false;  // distinguishes an empty quoted word '' from no word
  enum class Quote { None, Single, Double } quote = Quote::None;
  for (size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (quote == Quote::Single) {
      if (c == '\'') quote = Quote::None; else cur += c;
    } else if (quote == Quote::Double) {
      if (c == '"') {
        quote = Quote::None;
      } else if (c == '\\' && i + 1 < s.size() && std::string_view("\"\\$`\n").find(s[i + 1]) !=
                                                       std::string_view::npos) {
        if (s[++i] != '\n') cur += s[i];
      } else {
        cur += c;
      }
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      if (have) words.push_back(std::move(cur));
      cur.clear();
      have = false;
    } else if (c == '\'' || c == '"') {
      quote = c == '\'' ? Quote::Single : Quote::Double;
      have = true;
    } else if (c == '\\' && i + 1 < s.size()) {
      if (s[++i] != '\n') cur += s[i];
      have = true;
    } else {
      cur += c;
      have = true;
    }
  }
  if (quote != Quote::None) {
    throw ComposeError(where + ": unterminated " + (quote == Quote::Single ? "'" : "\"") +
                       " in command \"" + std::string(s) + "\"");
  }
  if (have) words.push_back(std::move(cur));
  return words;
}

std::map<std::string, std::string> parseDotEnv(std::string_view text, const std::string& where) {
  std::map<std::string, std::string> vars;
  size_t line_no = 0;
  while (!text.empty()) {
    ++line_no;
    const size_t nl = text.find('\n');
    std::string line = trim(text.substr(0, nl));
    text = nl == std::string_view::npos ? std::string_view() : text.substr(nl + 1);
    if (line.empty() || line[0] == '#') continue;
    if (line.rfind("export ", 0) == 0) line = trim(std::string_view(line).substr(7));
    const size_t eq = line.find('=');
    const std::string at = where + ":" + std::to_string(line_no);
    if (eq == std::string::npos) throw ComposeError(at + ": expected KEY=VALUE, got \"" + line + "\"");
    const std::string key = trim(std::string_view(line).substr(0, eq));
    if (key.empty() || !isNameStart(key[0])) throw ComposeError(at + ": bad variable name \"" + key + "\"");
    for (char c : key) {
      if (!isNameChar(c)) throw ComposeError(at + ": bad variable name \"" + key + "\"");
    }
    std::string raw = trim(std::string_view(line).substr(eq + 1));
    std::string value;
    if (!raw.empty() && (raw[0] == '"' || raw[0] == '\'')) {
      const char q = raw[0];
      size_t i = 1;
      for (; i < raw.size() && raw[i] != q; ++i) {
        if (q == '"' && raw[i] == '\\' && i + 1 < raw.size()) {
          const char e = raw[++i];
          value += e == 'n' ? '\n' : e == 't' ? '\t' : e;
        } else {
          value += raw[i];
        }
      }
      if (i >= raw.size()) throw ComposeError(at + ": unterminated quote");
    } else {
      // An unquoted value ends at " #" (an inline comment), as docker compose reads it.
      for (size_t i = 0; i < raw.size(); ++i) {
        if (raw[i] == '#' && i > 0 && std::isspace(static_cast<unsigned char>(raw[i - 1]))) {
          raw.resize(i);
          break;
        }
      }
      value = trim(raw);
    }
    vars[key] = value;
  }
  return vars;
}

std::string quoteCommand(const std::vector<std::string>& argv) {
  std::string out;
  for (const std::string& word : argv) {
    if (!out.empty()) out += ' ';
    bool safe = !word.empty();
    for (char c : word) {
      safe = safe && (std::isalnum(static_cast<unsigned char>(c)) ||
                      std::string_view("_@%+=:,./-").find(c) != std::string_view::npos);
    }
    if (safe) {
      out += word;
      continue;
    }
    out += '\'';
    for (char c : word) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    out += '\'';
  }
  return out;
}

}  // namespace tessera::launcher
