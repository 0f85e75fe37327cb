#pragma once
// Tokens of the procman configuration language, with their line numbers.
// Comments run from '#' to the end of the line; a comment of the form
// "# @default NAME = VALUE" is handed to the parser as a kDefault token.
#include <string>
#include <vector>

namespace ivoa::launcher {

enum class TokenKind { kIdentifier, kString, kNumber, kLeftBrace, kRightBrace, kAssign, kSemicolon, kDefault, kEnd };

struct Token {
  TokenKind kind = TokenKind::kEnd;
  std::string text;  // identifier, string contents (unescaped), number, or the default's "NAME=VALUE" body
  int line = 0;
};

// Throws ConfigError ("PATH:LINE: ...") for an unterminated string or a
// character that cannot start a token.
std::vector<Token> tokenize(const std::string& text, const std::string& path);

// How a token reads in an error message: 'exec', "a string", end of file.
std::string describe(const Token& token);

}  // namespace ivoa::launcher
