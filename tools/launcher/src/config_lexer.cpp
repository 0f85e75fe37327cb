#include "config_lexer.hpp"

#include <cctype>

#include "ivoa/launcher/config.hpp"

namespace ivoa::launcher {
namespace {

bool is_identifier_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool is_identifier_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-';
}

std::string trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  const auto end = s.find_last_not_of(" \t\r");
  return s.substr(begin, end - begin + 1);
}

class Lexer {
 public:
  Lexer(const std::string& text, const std::string& path) : text_(text), path_(path) {}

  std::vector<Token> run() {
    std::vector<Token> tokens;
    while (skip_space_and_comments(tokens), pos_ < text_.size()) tokens.push_back(next());
    tokens.push_back({TokenKind::kEnd, "", line_});
    return tokens;
  }

 private:
  [[noreturn]] void fail(int line, const std::string& what) const {
    throw ConfigError(path_ + ":" + std::to_string(line) + ": " + what);
  }

  void skip_space_and_comments(std::vector<Token>& tokens) {
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (c == '\n') {
        ++line_;
        ++pos_;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        ++pos_;
      } else if (c == '#') {
        const auto end = text_.find('\n', pos_);
        const std::string body =
            trim(text_.substr(pos_ + 1, end == std::string::npos ? std::string::npos : end - pos_ - 1));
        if (body.rfind("@default", 0) == 0) tokens.push_back({TokenKind::kDefault, trim(body.substr(8)), line_});
        pos_ = end == std::string::npos ? text_.size() : end;
      } else {
        return;
      }
    }
  }

  Token next() {
    const char c = text_[pos_];
    switch (c) {
      case '{': ++pos_; return {TokenKind::kLeftBrace, "{", line_};
      case '}': ++pos_; return {TokenKind::kRightBrace, "}", line_};
      case '=': ++pos_; return {TokenKind::kAssign, "=", line_};
      case ';': ++pos_; return {TokenKind::kSemicolon, ";", line_};
      case '"': return string_token();
      default: break;
    }
    if (is_identifier_start(c)) return run_of(TokenKind::kIdentifier, is_identifier_char);
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '.')
      return run_of(TokenKind::kNumber, [](char d) { return std::isdigit(static_cast<unsigned char>(d)) || d == '.'; });
    fail(line_, std::string("unexpected character '") + c + "'");
  }

  template <class Pred>
  Token run_of(TokenKind kind, Pred pred) {
    const size_t begin = pos_++;
    while (pos_ < text_.size() && pred(text_[pos_])) ++pos_;
    return {kind, text_.substr(begin, pos_ - begin), line_};
  }

  Token string_token() {
    const int start_line = line_;
    std::string value;
    for (++pos_; pos_ < text_.size(); ++pos_) {
      char c = text_[pos_];
      if (c == '"') {
        ++pos_;
        return {TokenKind::kString, value, start_line};
      }
      if (c == '\n') ++line_;
      if (c == '\\' && pos_ + 1 < text_.size()) {
        c = text_[++pos_];
        if (c == 'n') c = '\n';
        else if (c == 't') c = '\t';
        else if (c != '"' && c != '\\') value += '\\';  // keep unknown escapes for the shell
      }
      value += c;
    }
    fail(start_line, "unterminated string");
  }

  const std::string& text_;
  const std::string& path_;
  size_t pos_ = 0;
  int line_ = 1;
};

}  // namespace

std::vector<Token> tokenize(const std::string& text, const std::string& path) { return Lexer(text, path).run(); }

std::string describe(const Token& token) {
  switch (token.kind) {
    case TokenKind::kEnd: return "end of file";
    case TokenKind::kString: return "\"" + token.text + "\"";
    case TokenKind::kDefault: return "'# @default' comment";
    default: return "'" + token.text + "'";
  }
}

}  // namespace ivoa::launcher
