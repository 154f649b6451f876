// The error is an undeclared name: Mesa reports it with source-string number 0.
int broken() {
    return undeclared_name; // BROKEN_MARKER
}
