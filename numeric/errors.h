// SPDX-License-Identifier: Apache-2.0
#pragma once
// Small typed exceptions shared by every impulse library. Library code throws; `main` catches,
// prints the one-line message and exits non-zero (docs/contributing.md "Errors").

#include <stdexcept>
#include <string>

namespace impulse {

/// Base of impulse's errors: `what()` is the complete one-line message.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A scene file or override is malformed: message is "file:line:col: key = value: expected ...".
class SceneError : public Error {
public:
    using Error::Error;
};

/// A value is outside its valid range or otherwise unusable.
class ValueError : public Error {
public:
    using Error::Error;
};

/// A file could not be read or written; message carries the library's own text.
class IoError : public Error {
public:
    using Error::Error;
};

/// A request would exceed the configured memory or impulse budget; message gives the estimate.
class BudgetError : public Error {
public:
    using Error::Error;
};

}  // namespace impulse
