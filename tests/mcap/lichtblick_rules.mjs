// The rules by which Lichtblick's JSON Schema parser (parseJsonSchema in its
// packages/mcap-support) turns a `jsonschema` channel's schema into the message definitions that
// its panels browse and its message paths are checked against, restated from reading it. A
// schema it rejects makes Lichtblick drop the channel when it opens the file (or when a live
// server advertises it).
//
// lichtblickFields(schema, name) returns the fields the parser defines, as a Map from path
// ("layers.control.kick_ball.activation", "queue[]") to the parser's type ("float64", "string",
// "uint32", "bool", ...), or throws with the reason the parser would give.

function integerType(schema) {
  const nonNegative =
    (typeof schema.minimum === "number" && schema.minimum >= 0) ||
    (typeof schema.exclusiveMinimum === "number" && schema.exclusiveMinimum >= 0);
  return nonNegative ? "uint32" : "int32";
}

function addFields(schema, typeName, keyPath, fields) {
  if (schema === null || typeof schema !== "object" || schema.type !== "object") {
    throw new Error(
      `Expected "type": "object" for schema ${typeName}, got ${JSON.stringify(schema?.type)}`,
    );
  }
  for (const [name, field] of Object.entries(schema.properties ?? {})) {
    const path = [...keyPath, name].join(".");
    if (field === null || typeof field !== "object") {
      throw new Error(`Unsupported type undefined for ${path}`);
    }
    if (Array.isArray(field.oneOf)) {
      // Enumerations: constants named by their titles, the field itself a uint32.
      if (!field.oneOf.every((alternative) => typeof alternative?.const === "number")) {
        throw new Error(
          `Unsupported type for ${path}: oneOf alternatives must have number values`,
        );
      }
      fields.set(path, "uint32");
      continue;
    }
    switch (field.type) {
      case "boolean":
        fields.set(path, "bool");
        break;
      case "string":
        if (field.contentEncoding === undefined) fields.set(path, "string");
        else if (field.contentEncoding === "base64") fields.set(`${path}[]`, "uint8");
        else throw new Error(`Unsupported contentEncoding ${JSON.stringify(field.contentEncoding)} in ${path}`);
        break;
      case "number":
        fields.set(path, "float64");
        break;
      case "integer":
        fields.set(path, integerType(field));
        break;
      case "object":
        fields.set(path, `${typeName}.${name}`);
        addFields(field, `${typeName}.${name}`, [...keyPath, name], fields);
        break;
      case "array": {
        const items = field.items;
        if (items === null || typeof items !== "object") {
          throw new Error(`Unsupported type undefined for array item ${path}`);
        }
        switch (items.type) {
          case "boolean":
            fields.set(`${path}[]`, "bool");
            break;
          case "string":
            if (items.contentEncoding !== undefined) {
              throw new Error(
                `Unsupported contentEncoding ${JSON.stringify(items.contentEncoding)} for array item ${path}`,
              );
            }
            fields.set(`${path}[]`, "string");
            break;
          case "number":
            fields.set(`${path}[]`, "float64");
            break;
          case "integer":
            fields.set(`${path}[]`, integerType(items));
            break;
          case "object":
            fields.set(`${path}[]`, `${typeName}.${name}`);
            addFields(items, `${typeName}.${name}`, [...keyPath, `${name}[]`], fields);
            break;
          default:
            throw new Error(`Unsupported type ${JSON.stringify(items.type)} for array item ${path}`);
        }
        break;
      }
      default:
        // "null", a list of types, or none at all.
        throw new Error(`Unsupported type ${JSON.stringify(field.type)} for ${path}`);
    }
  }
}

export function lichtblickFields(schema, name) {
  const fields = new Map();
  addFields(schema, name, [], fields);
  return fields;
}
