// SPDX-License-Identifier: Apache-2.0
// A small recursive-descent parser for the arithmetic expressions of spectrum and
// autocorrelation kernels, compiled to a postfix program evaluated on a fixed stack.
//
// Grammar (precedence from low to high; ^ is right-associative and binds tighter than a
// unary sign, as in mathematics: -2^2 = -4, 2^-1 = 0.5):
//     expr    := term   (('+' | '-') term)*
//     term    := unary  (('*' | '/') unary)*
//     unary   := ('-' | '+') unary | power
//     power   := primary ('^' unary)?
//     primary := number | name | name '(' expr (',' expr)* ')' | '(' expr ')'

#include <cctype>
#include <cmath>
#include <numbers>
#include <sstream>

#include "kernels/kernels.h"
#include "numeric/errors.h"

namespace impulse::kernels {
namespace {

enum Code { kConst, kVar, kNeg, kAdd, kSub, kMul, kDiv, kPow, kCall1, kCall2 };

struct Function {
    const char* name;
    int arity;
};
constexpr Function kFunctions[] = {{"exp", 1}, {"log", 1}, {"sqrt", 1}, {"abs", 1}, {"sin", 1},
                                   {"cos", 1}, {"tan", 1}, {"pow", 2},  {"min", 2}, {"max", 2}};
constexpr int kMaxStack = 64;

std::string function_list() {
    std::string s;
    for (const auto& f : kFunctions) {
        if (!s.empty()) s += ' ';
        s += f.name;
    }
    return s;
}

class Parser {
public:
    Parser(std::string_view text, const std::vector<std::string>& variables,
           std::vector<Expression::Op>& program, std::vector<bool>& used)
        : m_text(text), m_vars(variables), m_prog(program), m_used(used) {}

    void parse() {
        skip();
        if (m_pos >= m_text.size()) fail(m_pos, "expected an expression");
        expr();
        skip();
        if (m_pos < m_text.size())
            fail(m_pos, "expected an operator (+ - * / ^) or the end, found \"" +
                            std::string(1, m_text[m_pos]) + "\"");
    }

private:
    [[noreturn]] void fail(size_t pos, const std::string& what) const {
        std::ostringstream s;
        s << "expression \"" << m_text << "\": at column " << pos + 1 << ": " << what;
        throw ValueError(s.str());
    }
    void skip() {
        while (m_pos < m_text.size() && std::isspace(static_cast<unsigned char>(m_text[m_pos])))
            ++m_pos;
    }
    bool accept(char c) {
        skip();
        if (m_pos < m_text.size() && m_text[m_pos] == c) {
            ++m_pos;
            return true;
        }
        return false;
    }
    void emit(int code, int index = 0, double value = 0.0) {
        m_prog.push_back({code, index, value});
        // Track the stack depth so evaluation never overflows its fixed array.
        if (code == kConst || code == kVar)
            ++m_depth;
        else if (code != kNeg && code != kCall1)
            --m_depth;
        m_max_depth = std::max(m_max_depth, m_depth);
        if (m_max_depth > kMaxStack) fail(m_pos, "expression nested too deeply");
    }
    std::string expected_operand() const {
        std::string vars;
        for (const auto& v : m_vars) {
            if (!vars.empty()) vars += ", ";
            vars += v;
        }
        return "expected a number, a variable (" + vars + "), pi, e, a function (" +
               function_list() + ") or \"(\"";
    }

    void expr() {
        term();
        for (;;) {
            if (accept('+'))
                term(), emit(kAdd);
            else if (accept('-'))
                term(), emit(kSub);
            else
                return;
        }
    }
    void term() {
        unary();
        for (;;) {
            if (accept('*'))
                unary(), emit(kMul);
            else if (accept('/'))
                unary(), emit(kDiv);
            else
                return;
        }
    }
    void unary() {
        if (accept('-')) {
            unary();
            emit(kNeg);
        } else if (accept('+')) {
            unary();
        } else {
            power();
        }
    }
    void power() {
        primary();
        if (accept('^')) {
            unary();
            emit(kPow);
        }
    }
    void primary() {
        skip();
        if (m_pos >= m_text.size()) fail(m_pos, expected_operand() + ", found the end");
        const char c = m_text[m_pos];
        if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number();
        if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') return name();
        if (accept('(')) {
            const size_t open = m_pos - 1;
            expr();
            if (!accept(')')) {
                skip();
                fail(m_pos,
                     "expected \")\" to close the \"(\" at column " + std::to_string(open + 1));
            }
            return;
        }
        fail(m_pos, expected_operand() + ", found \"" + std::string(1, c) + "\"");
    }
    void number() {
        const size_t start = m_pos;
        auto digits = [&] {
            size_t n = 0;
            while (m_pos < m_text.size() && std::isdigit(static_cast<unsigned char>(m_text[m_pos])))
                ++m_pos, ++n;
            return n;
        };
        size_t n = digits();
        if (m_pos < m_text.size() && m_text[m_pos] == '.') {
            ++m_pos;
            n += digits();
        }
        if (n == 0) fail(start, "expected digits in a number");
        // An exponent only when digits follow ("2e3", "2e-3"); "2*e" uses the constant e.
        if (m_pos < m_text.size() && (m_text[m_pos] == 'e' || m_text[m_pos] == 'E')) {
            size_t p = m_pos + 1;
            if (p < m_text.size() && (m_text[p] == '+' || m_text[p] == '-')) ++p;
            if (p < m_text.size() && std::isdigit(static_cast<unsigned char>(m_text[p]))) {
                m_pos = p;
                digits();
            }
        }
        const std::string s(m_text.substr(start, m_pos - start));
        emit(kConst, 0, std::strtod(s.c_str(), nullptr));
    }
    void name() {
        const size_t start = m_pos;
        while (m_pos < m_text.size() &&
               (std::isalnum(static_cast<unsigned char>(m_text[m_pos])) || m_text[m_pos] == '_'))
            ++m_pos;
        const std::string id(m_text.substr(start, m_pos - start));
        if (accept('(')) {
            for (int f = 0; f < int(std::size(kFunctions)); ++f) {
                if (id != kFunctions[f].name) continue;
                expr();
                for (int a = 1; a < kFunctions[f].arity; ++a) {
                    if (!accept(',')) {
                        skip();
                        fail(m_pos, "expected \",\": " + id + " takes " +
                                        std::to_string(kFunctions[f].arity) + " arguments");
                    }
                    expr();
                }
                if (!accept(')')) {
                    skip();
                    fail(m_pos, "expected \")\" after the " + std::to_string(kFunctions[f].arity) +
                                    " argument" + (kFunctions[f].arity > 1 ? "s" : "") + " of " +
                                    id);
                }
                emit(kFunctions[f].arity == 1 ? kCall1 : kCall2, f);
                return;
            }
            fail(start, "unknown function \"" + id + "\": expected one of " + function_list());
        }
        for (size_t v = 0; v < m_vars.size(); ++v)
            if (id == m_vars[v]) {
                m_used[v] = true;
                emit(kVar, static_cast<int>(v));
                return;
            }
        if (id == "pi") return emit(kConst, 0, std::numbers::pi);
        if (id == "e") return emit(kConst, 0, std::numbers::e);
        for (const auto& f : kFunctions)
            if (id == f.name) fail(m_pos, "expected \"(\" after the function " + id);
        fail(start, expected_operand() + ", found \"" + id + "\"");
    }

    std::string_view m_text;
    const std::vector<std::string>& m_vars;
    std::vector<Expression::Op>& m_prog;
    std::vector<bool>& m_used;
    size_t m_pos = 0;
    int m_depth = 0, m_max_depth = 0;
};

}  // namespace

Expression::Expression(std::string_view text, std::vector<std::string> variables)
    : m_text(text), m_variables(std::move(variables)), m_used(m_variables.size(), false) {
    Parser(m_text, m_variables, m_program, m_used).parse();
}

bool Expression::uses(std::string_view variable) const {
    for (size_t i = 0; i < m_variables.size(); ++i)
        if (m_variables[i] == variable) return m_used[i];
    return false;
}

double Expression::evaluate(std::span<const double> values) const {
    double st[kMaxStack];
    int top = -1;
    for (const Op& op : m_program) {
        switch (op.code) {
            case kConst:
                st[++top] = op.value;
                break;
            case kVar:
                st[++top] = values[op.index];
                break;
            case kNeg:
                st[top] = -st[top];
                break;
            case kAdd:
                --top, st[top] += st[top + 1];
                break;
            case kSub:
                --top, st[top] -= st[top + 1];
                break;
            case kMul:
                --top, st[top] *= st[top + 1];
                break;
            case kDiv:
                --top, st[top] /= st[top + 1];
                break;
            case kPow:
                --top, st[top] = std::pow(st[top], st[top + 1]);
                break;
            case kCall1: {
                double& x = st[top];
                switch (op.index) {
                    case 0:
                        x = std::exp(x);
                        break;
                    case 1:
                        x = std::log(x);
                        break;
                    case 2:
                        x = std::sqrt(x);
                        break;
                    case 3:
                        x = std::abs(x);
                        break;
                    case 4:
                        x = std::sin(x);
                        break;
                    case 5:
                        x = std::cos(x);
                        break;
                    case 6:
                        x = std::tan(x);
                        break;
                }
                break;
            }
            case kCall2: {
                --top;
                double& a = st[top];
                const double b = st[top + 1];
                switch (op.index) {
                    case 7:
                        a = std::pow(a, b);
                        break;
                    case 8:
                        a = std::min(a, b);
                        break;
                    case 9:
                        a = std::max(a, b);
                        break;
                }
                break;
            }
        }
    }
    return st[0];
}

}  // namespace impulse::kernels
