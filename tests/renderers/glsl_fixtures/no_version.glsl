// No version line here.
void main() {}
